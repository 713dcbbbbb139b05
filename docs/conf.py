"""Sphinx configuration of the gnibench documentation.

Build (warnings are errors, every cross-reference must resolve, the notebooks execute)::

    pip install -e '.[docs]'
    python -m sphinx -W --keep-going -n -b html docs docs/_build/html

The site opens from ``file://`` and needs no network: the intersphinx inventories are files in
``docs/_inv/`` and MathJax is served from the build (package ``jupyter-server-mathjax``).
The reference pages (registries, CLI, schemas, claims), the gallery and the performance page are
generated when the build starts (``docs/_ext/gnibench_docs``).
"""
from __future__ import annotations

import os
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
sys.path.insert(0, str(DOCS / "_ext"))

import gnibench  # noqa: E402

# The executed pages run shell commands through bash (their helper `sh`): `gnibench` is the
# command of this interpreter's environment, and a command line stops at its first failing
# command (a failed command fails the build, as a failed Python cell does).
os.environ["PATH"] = str(Path(sys.executable).parent) + os.pathsep + os.environ.get("PATH", "")
os.environ["BASH_ENV"] = str(DOCS / "_ext" / "bash_env.sh")

project = "gnibench"
author = "the gnibench developers"
copyright = "the gnibench developers, MIT licence"
release = gnibench.__version__
version = release

extensions = [
    "myst_nb",
    "sphinx.ext.autodoc",
    "numpydoc",
    "sphinx.ext.intersphinx",
    "sphinx.ext.mathjax",
    "sphinxcontrib.bibtex",
    "sphinx_copybutton",
    "gnibench_docs",
]

# changelog fragments of the helpers (merged into CHANGELOG.md), the build and the helpers' files
exclude_patterns = ["_build", "changes", "changes/*", "_ext", "_inv", "**/.ipynb_checkpoints",
                    "**/_overview.md",
                    "Thumbs.db", ".DS_Store"]
source_suffix = {".rst": "restructuredtext", ".md": "myst-nb", ".ipynb": "myst-nb"}
root_doc = "index"
nitpicky = True
# Internal modules below the public API are not part of the reference: a docstring's reference to
# one (``gnibench.suite....``) renders as code instead of a link.
nitpick_ignore_regex = [(r"py:.*", r"gnibench\.(suite|methods|problems|reports)\..*"),
                        # the column tuples of gnibench.list_* (named in their docstrings)
                        (r"py:data", r"(PROBLEM|METHOD|METRIC)_COLUMNS")]
suppress_warnings = ["myst.header"]

# --- MyST and MyST-NB -------------------------------------------------------------------------
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist", "substitution"]
myst_heading_anchors = 3
nb_execution_mode = "cache"                     # re-run a notebook only when its code changed
nb_execution_cache_path = str(DOCS / "_build" / ".jupyter_cache")
nb_execution_raise_on_error = True              # a failed cell fails the build
nb_execution_show_tb = True
nb_execution_timeout = 900
nb_execution_in_temp = True                     # the notebooks write into a temporary folder
nb_render_markdown_format = "myst"             # Markdown outputs with tables (commonmark has none)
nb_merge_streams = True                         # one output block per stream and cell
nb_output_stderr = "remove"                     # progress lines (stderr) are not shown; a failure
                                                # still fails the build

# --- API reference: autodoc + numpydoc --------------------------------------------------------
autodoc_typehints = "none"                      # numpydoc's Parameters section says the types
autodoc_member_order = "bysource"
numpydoc_show_class_members = False
numpydoc_xref_param_type = True
numpydoc_xref_ignore = "all"                    # only the aliases below become links
numpydoc_xref_aliases = {
    "DataFrame": "pandas.DataFrame", "pandas.DataFrame": "pandas.DataFrame",
    "Path": "pathlib.Path", "pathlib.Path": "pathlib.Path",
    "ndarray": "numpy.ndarray", "numpy.ndarray": "numpy.ndarray",
    "Trajectory": "gnibench.Trajectory", "RunResult": "gnibench.RunResult",
    "UserError": "gnibench.UserError", "gnibench.UserError": "gnibench.UserError",
    "Figure": "matplotlib.figure.Figure",
}
# every public function shows its parameters and an example (issue 39): a missing section is a
# warning, so an error of the build
numpydoc_validation_checks = {"PR01", "RT01", "EX01"}
# the records (RunResult, Trajectory) are returned, never built by users: their fields are
# documented as Attributes, with the class's example, and their properties as one line
numpydoc_validation_exclude = {r"\.__init__$", r"\.__repr__$",
                               r"^gnibench\.(RunResult|Trajectory)(\.\w+)?$"}

# --- intersphinx, from local inventories (docs/_inv: no network at build time) ----------------
_INV = DOCS / "_inv"
intersphinx_mapping = {
    "python": ("https://docs.python.org/3", str(_INV / "python.inv")),
    "numpy": ("https://numpy.org/doc/stable", str(_INV / "numpy.inv")),
    "scipy": ("https://docs.scipy.org/doc/scipy", str(_INV / "scipy.inv")),
    "pandas": ("https://pandas.pydata.org/docs", str(_INV / "pandas.inv")),
    "heyoka": ("https://bluescarni.github.io/heyoka.py", str(_INV / "heyoka.inv")),
    "rebound": ("https://rebound.readthedocs.io/en/latest", str(_INV / "rebound.inv")),
    "matplotlib": ("https://matplotlib.org/stable", str(_INV / "matplotlib.inv")),
}
intersphinx_disabled_reftypes = ["std:doc"]    # Sphinx's default: objects, never whole pages

# --- bibliography -----------------------------------------------------------------------------
bibtex_bibfiles = ["references.bib"]
bibtex_default_style = "plain"
bibtex_reference_style = "author_year"

# --- math, served from the build (no CDN) -----------------------------------------------------
import jupyter_server_mathjax  # noqa: E402

html_static_path = ["_static", str(Path(jupyter_server_mathjax.__file__).parent / "static")]
mathjax_path = "MathJax.js?config=TeX-AMS-MML_HTMLorMML-full"
# MathJax 2 (the version that package ships): MyST marks pages tex2jax_ignore and the math
# elements "math", so MathJax processes exactly those
mathjax2_config = {"tex2jax": {"processClass": "tex2jax_process|mathjax_process|math|output_area",
                               "ignoreClass": "tex2jax_ignore|mathjax_ignore"},
                   "TeX": {"equationNumbers": {"autoNumber": "none"}}}

# --- HTML -------------------------------------------------------------------------------------
html_theme = "pydata_sphinx_theme"
html_title = f"gnibench {release}"
html_css_files = ["gnibench.css"]
html_theme_options = {
    "navbar_align": "left",
    "show_toc_level": 2,
    "navigation_with_keys": False,
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version"],
}
html_sidebars = {"index": [], "bibliography": []}
html_show_sourcelink = False
copybutton_prompt_text = r"\$ |>>> |\.\.\. "
copybutton_prompt_is_regexp = True
