"""Reference pages of the public interfaces, generated from the code itself:

* ``reference/cli.md``: every command's ``--help``, as the installed ``gnibench`` prints it (the
  argparse parser is the single source; the commands are read from the top-level usage line);
* ``reference/api.md``: autodoc (numpydoc) of every name in ``gnibench.__all__`` and of the
  public subpackages (``gnibench.plot`` where it exists);
* ``reference/input-files.md``'s tables: the ``gnibench-schema`` directive renders the keys of
  the TOML schemas from their pydantic records (:mod:`gnibench.suite.cli.schema_docs`).
"""
from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

from docutils import nodes
from docutils.statemachine import StringList
from sphinx.util.docutils import SphinxDirective

from .common import Tree

# --- the command line -------------------------------------------------------------------------

CLI_INTRO = """# Command line

`gnibench COMMAND ...`: each command below is a thin shell on the Python API
({doc}`/reference/api`): it parses its arguments, calls the library and prints. This page is
each command's `--help`, as the installed command prints it.

Bad input gives one line on stderr naming the bad value and what is allowed, exit code 2, and
writes nothing. Exit codes: 0; 1 for a verdict or comparison that failed, or a fault during work
(a full disk); 2 for bad input; 130 and 143 for SIGINT and SIGTERM (what was finished is kept).
"""


def _help(args: list[str]) -> str:
    env = dict(os.environ, COLUMNS="100", NO_COLOR="1")
    cmd = [sys.executable, "-m", "gnibench.suite.cli.entry", *args, "--help"]
    out = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=120)
    if out.returncode != 0:
        raise RuntimeError(f"{' '.join(args)} --help failed: {out.stderr.strip()}")
    return out.stdout.rstrip()


def commands() -> list[str]:
    """The commands, from the top-level usage line ``gnibench [-h] {solve,list,...} ...``."""
    m = re.search(r"\{([\w,-]+)\}", _help([]))
    return m.group(1).split(",") if m else []


def cli_page() -> str:
    out = [CLI_INTRO, "```text\n" + _help([]) + "\n```\n"]
    for c in commands():
        out.append(f"(cli-{c})=\n## `gnibench {c}`\n\n```text\n{_help([c])}\n```\n")
    return "\n".join(out)


# --- the Python API ---------------------------------------------------------------------------

API_INTRO = """# Python API

Everything the command line does is a function of the package `gnibench` (`import gnibench` is
cheap: numba, sympy and pandas load on the first call). Every function checks its arguments
before any work and raises {class}`gnibench.UserError` with the one line the command line
prints; a diverging integration is a status, not an exception. The examples below are run as
doctests by the test suite.
"""


def api_names() -> list[str]:
    import gnibench

    return list(gnibench.__all__)


def api_page() -> str:
    import importlib
    import inspect

    import gnibench

    out = [API_INTRO]
    functions, classes = [], []
    first = ["solve", "run", "verify", "reproduce", "report", "load"]
    names = sorted(api_names(), key=lambda n: (n not in first, first.index(n) if n in first else 0, n))
    for name in names:
        obj = getattr(gnibench, name)
        (classes if inspect.isclass(obj) else functions).append(name)
    out.append("## Functions\n")
    for name in functions:
        out.append(f"```{{eval-rst}}\n.. autofunction:: gnibench.{name}\n```\n")
    out.append("## Records and errors\n")
    for name in classes:
        out.append(f"```{{eval-rst}}\n.. autoclass:: gnibench.{name}\n   :members:\n```\n")
    for sub in ("plot",):
        try:
            importlib.import_module(f"gnibench.{sub}")
        except ImportError:
            continue
        out.append(f"## `gnibench.{sub}`\n")
        out.append(f"```{{eval-rst}}\n.. automodule:: gnibench.{sub}\n   :members:\n```\n")
    return "\n".join(out)


def write(srcdir: Path) -> None:
    tree = Tree(srcdir / "reference")
    tree.write("cli.md", cli_page())
    tree.write("api.md", api_page())


# --- the TOML schemas -------------------------------------------------------------------------

class SchemaDirective(SphinxDirective):
    """```{gnibench-schema} NAME``` renders the key tables of one schema (experiment, group,
    points, scales, figure, claim, definitions) from its records."""

    required_arguments = 1

    def run(self):
        from gnibench.suite.cli import schema_docs

        text = schema_docs.render(self.arguments[0])
        node = nodes.container(classes=["gnibench-schema"])
        self.state.nested_parse(StringList(text.splitlines(), source="gnibench-schema"),
                                self.content_offset, node)
        return [node]


def statuses_table() -> str:
    """The statuses a cell can end with, from the one status enum (internal codes left out)."""
    from gnibench.suite.foundation.status import Status

    from .common import cell, code, table

    kinds = {"final": "the end", "failure": "a failure", "table": "in experiments"}
    rows = [[code(s.value), cell(kinds.get(s.kind, s.kind)), cell(s.doc)]
            for s in Status if s.kind != "internal"]
    return table(["status", "kind", "meaning"], rows)


class StatusesDirective(SphinxDirective):
    """```{gnibench-statuses}``` renders the table of statuses from
    :class:`gnibench.suite.foundation.status.Status`."""

    def run(self):
        node = nodes.container(classes=["gnibench-statuses"])
        self.state.nested_parse(StringList(statuses_table().splitlines(), source="gnibench-statuses"),
                                self.content_offset, node)
        return [node]
