"""Which tests can see a file: the reverse import graph of the package and its test modules.

Mutation testing (:mod:`.mutants`) runs, against each mutant, the test modules that import the
mutated file, directly or through other modules, rather than a hand-kept list. The graph is
computed from the source (:mod:`ast`, nothing is imported):

* its nodes are the package's modules (``gnibench.suite.runs.store`` for ``suite/runs/store.py``)
  and the test suite's files (``tests/runs/test_runner.py``; the shared helpers
  ``tests/support*.py`` import as top-level modules, ``support``);
* an edge goes from a module to every module it imports anywhere in its text, at the top or inside
  a function (the package imports most of its dependencies lazily, inside the function that needs
  them): ``import gnibench.a.b``, ``from gnibench.a import b`` (the submodule ``b`` when there is
  one, else ``gnibench.a``), ``from gnibench.a.b import name``; a package's parents are not
  counted (importing ``gnibench.a.b`` runs ``gnibench/__init__.py`` too, but ``gnibench`` itself
  only imports its API lazily, on first use of a name: that use is an import of
  ``gnibench.suite.api`` in ``__getattr__``, and so an edge of ``gnibench``);
* a test module that imports ``gnibench`` and uses ``gnibench.solve`` etc. thus depends on the API
  and everything below it.

:func:`tests_seeing` lists the test files whose import closure holds a file, nearest first (a
test that imports the module itself before one that reaches it through the API), so that with
pytest's ``-x`` the likeliest killers run first. A file that is not a Python module of the
package (a data file: the claims, the experiments, the catalog) is read through resources, not
imported: every test file sees it. ``tests/conftest.py`` is loaded for every test and is not a
test module; what it imports does not select tests.
"""
from __future__ import annotations

import ast
from collections import deque
from functools import lru_cache
from pathlib import Path

PACKAGE = "gnibench"
#: folders of the repository that are not part of the package's importable code
SKIP = {".git", ".venv", "__pycache__", "build", "dist", "results", "docs", "examples",
        "benchmarks", ".benchmarks"}


def module_of(path: str) -> str:
    """The node of a file given relative to the package root: a dotted module name for the
    package's files, the path itself for the test suite's."""
    p = Path(path)
    if p.parts and p.parts[0] == "tests":
        if p.name.startswith("support") and len(p.parts) == 2:
            return p.stem                              # tests/support*.py: top-level helpers
        return p.as_posix()
    parts = list(p.with_suffix("").parts)
    if parts and parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join([PACKAGE, *parts])


def _files(root: Path) -> list[Path]:
    out = []
    for f in sorted(root.rglob("*.py")):
        rel = f.relative_to(root)
        if any(part in SKIP or part.endswith(".egg-info") for part in rel.parts[:-1]):
            continue
        out.append(rel)
    return out


def _imports(tree: ast.AST, modules: set[str], here: str) -> set[str]:
    """The nodes ``tree`` imports (see the module docstring)."""
    found: set[str] = set()

    def add(name: str) -> None:
        while name and name not in modules:          # a name inside a module: the module
            name = name.rpartition(".")[0]
        if name:
            found.add(name)

    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                add(alias.name)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:                            # relative: from the importing package
                pkg = here.split(".")[: -node.level] if here.count(".") else []
                base = ".".join(pkg + ([base] if base else []))
            for alias in node.names:
                sub = f"{base}.{alias.name}" if base else alias.name
                add(sub if sub in modules else base)
    found.discard(here)
    return found


@lru_cache(maxsize=4)
def import_graph(root: str) -> dict[str, frozenset[str]]:
    """node -> the nodes it imports, over the package at ``root`` and its tests."""
    base = Path(root)
    files = _files(base)
    nodes = {module_of(str(f)): f for f in files}
    modules = set(nodes)
    graph = {}
    for node, rel in nodes.items():
        try:
            tree = ast.parse((base / rel).read_text(encoding="utf-8"), str(rel))
        except (SyntaxError, UnicodeDecodeError):
            tree = ast.Module(body=[], type_ignores=[])   # a mutant may break a file: no edges
        graph[node] = frozenset(_imports(tree, modules, node))
    return graph


def importers(graph: dict[str, frozenset[str]], target: str) -> dict[str, int]:
    """Every node whose imports reach ``target``, with its distance (``target`` itself: 0)."""
    reverse: dict[str, set[str]] = {}
    for node, deps in graph.items():
        for d in deps:
            reverse.setdefault(d, set()).add(node)
    dist = {target: 0}
    queue = deque([target])
    while queue:
        node = queue.popleft()
        for parent in sorted(reverse.get(node, ())):
            if parent not in dist:
                dist[parent] = dist[node] + 1
                queue.append(parent)
    return dist


def is_test_file(node: str) -> bool:
    name = Path(node).name
    return node.startswith("tests/") and name.startswith("test_") and name.endswith(".py")


def all_test_files(root: Path) -> list[str]:
    return sorted(n for n in import_graph(str(Path(root).resolve())) if is_test_file(n))


def tests_seeing(root: Path, file: str) -> list[str]:
    """The test files that can see ``file`` (relative to the package root ``root``), nearest
    importers first, then by name; every test file for a file that is not a module."""
    graph = import_graph(str(Path(root).resolve()))
    node = module_of(file)
    if not file.endswith(".py") or node not in graph:
        return all_test_files(root)
    dist = importers(graph, node)
    return sorted((n for n in dist if is_test_file(n)), key=lambda n: (dist[n], n))
