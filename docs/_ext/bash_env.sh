# Sourced by the bash of the executed pages' commands (docs/conf.py sets BASH_ENV): stop at the first
# failing command, so that a failed command fails the documentation build.
set -eo pipefail
