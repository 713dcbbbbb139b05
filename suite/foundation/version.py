"""The package version (``gnibench.__version__``; kept equal to pyproject.toml's by a test)."""
VERSION = "0.1.0"
