"""The API's docstrings (issue 39, item 5): every public name has numpydoc sections and an
``Examples`` section, and the examples run (doctest) with the outputs they show."""
from __future__ import annotations

import doctest
import inspect
import re

import gnibench
import pytest

PUBLIC = list(gnibench.__all__) + [f"plot.{n}" for n in gnibench.plot.__all__]


def _get(name: str):
    """A public name of gnibench, dotted names (``plot.work_precision``) included."""
    obj = gnibench
    for part in name.split("."):
        obj = getattr(obj, part)
    return obj


FUNCTIONS = [n for n in PUBLIC if inspect.isfunction(_get(n))]


def _sections(doc: str) -> set[str]:
    return set(re.findall(r"^\s*(\w[\w ]*)\n\s*-{3,}\s*$", doc, flags=re.MULTILINE))


@pytest.mark.parametrize("name", PUBLIC)
def test_every_public_name_has_an_example(name):
    doc = inspect.getdoc(_get(name)) or ""
    sections = _sections(doc)
    assert "Examples" in sections and ">>> " in doc.split("Examples")[1], name
    if name in FUNCTIONS:
        need = {"Returns"} | ({"Parameters"} if inspect.signature(_get(name)).parameters
                              else set())
        assert need <= sections, (name, sections)
        if name not in ("list_problems", "list_methods", "list_metrics"):
            assert "Raises" in sections, name


def _examples(obj) -> list[doctest.DocTest]:
    finder = doctest.DocTestFinder(recurse=False)
    return [t for t in finder.find(obj, name=f"gnibench.{obj.__name__}", globs={})
            if t.examples]


@pytest.mark.parametrize("name", PUBLIC)
def test_the_examples_run(name, tmp_path, monkeypatch):
    """Each docstring's examples, as doctests (in a temporary working directory; the user
    definitions an example loads are dropped afterwards)."""
    from gnibench.suite.cell.user.loader import loaded, unload

    monkeypatch.chdir(tmp_path)
    before = set(loaded())
    tests = _examples(_get(name))
    assert tests, name
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    try:
        for test in tests:
            runner.run(test)
    finally:
        for path in set(loaded()) - before:
            unload(path)
    result = runner.summarize(verbose=False)
    assert result.failed == 0, f"{result.failed} of {result.attempted} examples failed ({name})"


def test_the_how_to_page_runs(tmp_path, monkeypatch, capsys):
    """docs/how-to/python-api.md: its Python blocks run as they are, and print what it says."""
    from pathlib import Path

    monkeypatch.chdir(tmp_path)
    page = Path(__file__).resolve().parents[2] / "docs" / "how-to" / "python-api.md"
    blocks = re.findall(r"```python\n(.*?)```", page.read_text(encoding="utf-8"), flags=re.DOTALL)
    assert len(blocks) == 2
    for block in blocks:
        exec(compile(block, str(page), "exec"), {})                    # noqa: S102
    out = capsys.readouterr().out
    assert "gnibench.run: bad jobs '2' (a str); allowed: an integer, or None" in out
