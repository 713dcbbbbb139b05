"""The layout: one import package ``gnibench``, floors that import downwards only, no import cycle.

Floors, from the ground up (docs/explanation/architecture.md, kept equal to :data:`FLOORS` by
:func:`test_the_architecture_page_shows_the_floors`)::

    0 gnibench.suite.foundation   errors, parameter schemas and bounds, status, the verified cache
    1 gnibench.problems           problem records, sympy -> numba source
    2 gnibench.methods            method and modifier records, kernel assembly, external engines
    3 gnibench.suite.cell         specs, the typed cell, compiled cells, the driver, references
    4 gnibench.suite.metrics      measurements of a trajectory
    5 gnibench.suite.runs         experiments, runner, tables, storage, bench
    6 gnibench.suite.ledger       the claims ledger: entries, closed forms, identity checks, verdicts
    7 gnibench.reports            reports from tables
    8 gnibench.suite.api          the library's entry points, the Python API (the package top
                                  re-exports it)
    9 gnibench.suite.cli          the command line: parses arguments, calls the library, prints

A module may import from its own floor or below. Every import counts, also those made inside a
function (they are for start-up time only, never to dodge a circle).
"""
from __future__ import annotations

import ast
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE_DIRS = ("suite", "problems", "methods", "reports")
FLOORS = (
    ("gnibench.suite.foundation", 0),
    ("gnibench.problems", 1),
    ("gnibench.methods", 2),
    ("gnibench.suite.cell", 3),
    ("gnibench.suite.metrics", 4),
    ("gnibench.suite.runs", 5),
    ("gnibench.suite.ledger", 6),
    ("gnibench.reports", 7),
    ("gnibench.suite.api", 8),
    ("gnibench.suite.cli", 9),
)
# package markers with no code of their own (docstrings, the version)
NEUTRAL = {"gnibench", "gnibench.suite"}


def module_files() -> dict[str, Path]:
    """Module name -> file, for every module of the package."""
    out = {"gnibench": ROOT / "__init__.py"}
    for top in PACKAGE_DIRS:
        for path in sorted((ROOT / top).rglob("*.py")):
            rel = path.relative_to(ROOT).with_suffix("")
            parts = list(rel.parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join(["gnibench", *parts])] = path
    return out


def import_graph() -> dict[str, set[str]]:
    """Module -> the project modules it imports (anywhere in the file)."""
    files = module_files()
    graph: dict[str, set[str]] = {}
    for name, path in files.items():
        targets: set[str] = set()
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                mods = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                # `from pkg import mod` imports pkg.mod when it is a module of the project
                mods = [f"{node.module}.{a.name}" if f"{node.module}.{a.name}" in files
                        else node.module for a in node.names]
            else:
                continue
            targets.update(m for m in mods if m in files and m != name)
        graph[name] = targets
    return graph


def floor(module: str) -> int | None:
    best = None
    for prefix, level in FLOORS:
        if module == prefix or module.startswith(prefix + "."):
            best = level
    return best


def test_every_module_has_a_floor():
    missing = [m for m in module_files() if m not in NEUTRAL and floor(m) is None]
    assert not missing, f"modules outside every floor: {missing}"


def test_imports_go_downwards_only():
    graph = import_graph()
    up = [f"{src} (floor {floor(src)}) imports {dst} (floor {floor(dst)})"
          for src, dsts in graph.items() for dst in dsts
          if src not in NEUTRAL and dst not in NEUTRAL and floor(dst) > floor(src)]
    assert not up, "imports that go up a floor:\n" + "\n".join(sorted(up))


def test_the_library_does_not_import_the_command_line():
    """The library first, the command line on top: nothing below ``suite/cli`` imports it (the
    floors say so; this names the rule of issue 44 on its own, also for the package top)."""
    graph = import_graph()
    found = sorted(f"{src} imports {dst}" for src, dsts in graph.items() for dst in dsts
                   if dst.startswith("gnibench.suite.cli") and not src.startswith("gnibench.suite.cli"))
    assert not found, "\n".join(found)


def test_reports_read_tables_not_spec_texts():
    """The reports read the columns the runner writes from the typed cell (problem_id,
    base_method, modifiers, family, ...): they import no spec parser."""
    graph = import_graph()
    found = sorted(f"{src} imports {dst}" for src, dsts in graph.items() for dst in dsts
                   if src.startswith("gnibench.reports") and dst == "gnibench.suite.cell.spec")
    assert not found, "\n".join(found)


def test_no_module_class_assignment():
    """No module is given another class (``module.__class__ = ...``): the package's names are
    plain functions and subpackages."""
    found = []
    for name, path in module_files().items():
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Assign) and any(isinstance(t, ast.Attribute) and t.attr == "__class__"
                                                    for t in node.targets):
                found.append(f"{name}:{node.lineno}")
    assert not found, found


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module, or with a self-loop (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1 or v in graph.get(v, ()):
                out.append(sorted(comp))

    limit = sys.getrecursionlimit()
    sys.setrecursionlimit(10000)
    try:
        for v in sorted(graph):
            if v not in index:
                visit(v)
    finally:       # kept raised, it let later tests in the process parse deeper expressions
        sys.setrecursionlimit(limit)
    return out


def test_no_import_cycle():
    found = cycles(import_graph())
    assert not found, "import cycles:\n" + "\n".join(" <-> ".join(c) for c in found)


def test_cycle_detector_finds_a_planted_cycle():
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert cycles(graph) == [["a", "b", "c"]]
    assert cycles({"a": {"b"}, "b": set()}) == []


def _setup_packages() -> list[str]:
    """The package list setup.py derives (its ``packages()``, without running setup)."""
    import runpy

    return runpy.run_path(str(ROOT / "setup.py"), run_name="setup")["packages"](str(ROOT))


def test_the_package_list_is_derived_from_the_folders():
    """setup.py derives the packages (setuptools' discovery under the package folders, mapped
    into gnibench); pyproject.toml lists none by hand; every folder with an __init__.py is one."""
    doc = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert "packages" not in doc["tool"]["setuptools"]
    listed = set(_setup_packages())
    packages = {m for m, p in module_files().items() if p.name == "__init__.py"}
    assert listed == packages, (f"not found by setup.py: {sorted(packages - listed)}; "
                                f"found without an __init__.py: {sorted(listed - packages)}")


def test_a_wheel_holds_every_package_and_its_data(tmp_path):
    """A non-editable build (pip wheel, offline, as CI's ``pip install .`` builds it) holds every
    package, every file of pyproject.toml's package-data, and neither setup.py nor the tests."""
    import shutil
    import zipfile

    pytest.importorskip("wheel")
    src = tmp_path / "src"
    shutil.copytree(ROOT, src, ignore=shutil.ignore_patterns(
        ".git", "__pycache__", "*.egg-info", "build", "dist", "results", ".benchmarks", "docs",
        "tests", "benchmarks", "examples"))
    proc = subprocess.run([sys.executable, "-m", "pip", "wheel", str(src), "--no-deps",
                           "--no-build-isolation", "--no-index", "-q", "-w", str(tmp_path / "w")],
                          capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stderr[-3000:]
    (whl,) = (tmp_path / "w").glob("gnibench-*.whl")
    names = set(zipfile.ZipFile(whl).namelist())
    for package in _setup_packages():
        assert f"{package.replace('.', '/')}/__init__.py" in names, package
    data = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["package-data"]
    for package, patterns in data.items():
        folder = ROOT.joinpath(*package.split(".")[1:])
        for pattern in patterns:
            files = [p for p in folder.glob(pattern) if p.is_file()]
            assert files, (package, pattern)
            for f in files:
                assert f"gnibench/{f.relative_to(ROOT).as_posix()}" in names, f
    assert "gnibench/setup.py" not in names
    assert not [n for n in names if n.startswith(("tests/", "gnibench/tests/", "benchmarks/"))]
    modules = {f"gnibench/{p.relative_to(ROOT).as_posix()}" for p in module_files().values()}
    assert modules <= names, sorted(modules - names)[:5]


def test_only_gnibench_is_importable(tmp_path):
    """Installed, the project is `gnibench` and nothing else: `import suite` fails (run outside
    the repository, where the current directory would put the folders on sys.path)."""
    code = ("import importlib, gnibench.suite.cell.solve\n"
            "for name in ('suite', 'problems', 'methods', 'reports'):\n"
            "    try:\n"
            "        importlib.import_module(name)\n"
            "    except ModuleNotFoundError:\n"
            "        continue\n"
            "    raise SystemExit(f'{name} is importable')\n")
    proc = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, check=False,
                          text=True)
    assert proc.returncode == 0, proc.stderr + proc.stdout


def test_the_measured_durations_name_test_modules():
    """tests/durations.json (written by ``pytest --store-durations``; the modules are handed to
    the workers longest first, tests/conftest.py) holds a duration >= 0 for test modules that
    exist, and for most of them: a module renamed or removed, or a stale file, fails here."""
    from support_order import read_durations

    durations = read_durations()
    modules = {p.relative_to(ROOT / "tests").as_posix() for p in (ROOT / "tests").rglob("test_*.py")}
    assert durations, "tests/durations.json is missing: run pytest --store-durations"
    stale = sorted(set(durations) - modules)
    assert not stale, f"tests/durations.json names modules that do not exist: {stale}"
    assert all(v >= 0 for v in durations.values())
    missing = sorted(modules - set(durations))
    assert len(missing) <= len(modules) // 10, f"not measured yet (pytest --store-durations): {missing}"


def test_modules_are_handed_out_longest_first():
    """The order of the modules: measured durations, longest first; an unmeasured module at the
    median; ties in collection order."""
    from support_order import longest_first

    durations = {"a.py": 5.0, "b.py": 50.0, "c.py": 1.0, "d.py": 20.0}
    assert longest_first(["a.py", "b.py", "c.py", "d.py", "new.py", "e.py"], durations) == [
        "b.py", "d.py", "new.py", "e.py", "a.py", "c.py"]           # median 12.5
    assert longest_first(["x.py", "y.py"], {}) == ["x.py", "y.py"]


def test_test_modules_have_unique_basenames():
    """The test folders are not packages (pytest's rootdir-relative ``prepend`` import), so two
    test modules with one basename, in tests/ or benchmarks/, clash at collection."""
    seen: dict[str, str] = {}
    for folder in ("tests", "benchmarks"):
        for path in sorted((ROOT / folder).rglob("*.py")):
            if path.name in ("conftest.py", "__init__.py"):
                continue
            rel = path.relative_to(ROOT).as_posix()
            assert path.name not in seen, f"{rel} and {seen[path.name]} share a basename"
            seen[path.name] = rel


ARCHITECTURE = ROOT / "docs" / "explanation" / "architecture.md"


def test_the_architecture_page_shows_the_floors():
    """The floor diagram of docs/explanation/architecture.md is :data:`FLOORS`, in order, and
    every folder or file the page names (in backticks, or in the diagram) exists."""
    import re

    text = ARCHITECTURE.read_text(encoding="utf-8")
    diagram = text.split("```text\n", 1)[1].split("```", 1)[0]
    shown = [(int(m[1]), m[2]) for m in re.finditer(r"^(\d+)\s+(\S+/)", diagram, re.M)]
    expected = [(level, prefix.removeprefix("gnibench.").replace(".", "/") + "/")
                for prefix, level in sorted(FLOORS, key=lambda f: -f[1])]
    assert shown == expected
    named = set(re.findall(r"`((?:suite|problems|methods|reports|tests|benchmarks|examples|docs)"
                           r"/[\w./-]*)`", text))
    named |= {p for _, p in shown}
    assert named, "no paths found on the page"
    missing = sorted(p for p in named if not (ROOT / p).exists())
    assert not missing, f"the architecture page names paths that do not exist: {missing}"
