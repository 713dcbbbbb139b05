"""Mutation testing of the ledger (suite/ledger/mutants.py): the catalog is valid, a mutant is
applied to a copy only (never to the installed tree), and the machinery kills one at quick scale.
The full run (every mutant, the whole ledger and the catalog's tests) is the slow command
``gnibench verify --mutants`` (README, "Mutation testing")."""
from __future__ import annotations

import json
import os

import pytest
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.ledger import mutants as M


def test_the_catalog_applies_and_covers_the_asked_categories():
    catalog, settings = M.load_catalog()
    assert len(catalog) >= 25
    problems = [p for p in (M.check(m) for m in catalog) if p]
    assert not problems, problems
    files = {m.file for m in catalog}
    for needed in ("methods/modifiers.py", "methods/kernels/newton.py", "methods/kernels/driver.py",
                   "methods/dense_output.py", "methods/partitioned.py", "problems/kepler_ks.py",
                   "suite/cell/reference.py", "suite/metrics/position_in_orbit.py"):
        assert needed in files, needed
    for m in catalog:
        assert m.description and m.plausible, m.id
    for test in settings["tests"]:
        assert (M.package_root() / test).is_file(), test


def test_a_snippet_must_occur_exactly_once(tmp_path):
    copy = M.copy_package(tmp_path)
    twice = M.Mutant("x", "methods/kernels/newton.py", "dnorm", "dnorm2", "d", "p")
    assert "occurs" in M.check(twice, copy)
    with pytest.raises(UserError, match="refusing"):
        M.apply(twice, copy)
    missing = M.Mutant("y", "methods/kernels/newton.py", "no such text", "z", "d", "p")
    assert "occurs 0 times" in M.check(missing, copy)


def test_a_mutant_changes_the_copy_only(tmp_path):
    (catalog, _), root = M.load_catalog(), M.package_root()
    m = next(x for x in catalog if x.id == "invariant-error-sign")
    before = (root / m.file).read_text()
    copy = M.copy_package(tmp_path)
    M.apply(m, copy)
    assert m.replacement in (copy / m.file).read_text()
    assert (root / m.file).read_text() == before and ".venv" not in os.listdir(copy)


def test_the_machinery_kills_a_mutant_at_quick_scale(tmp_path):
    """One claim, one mutant: the copy imports its own mutated code (checked), the ledger turns
    unexpected on it, the unmutated baseline does not."""
    catalog, _ = M.load_catalog()
    m = next(x for x in catalog if x.id == "invariant-error-sign")
    doc = M.run_mutants([m], tmp_path, scale="quick", jobs=1, claims=["HLW-1.2-d"], tests=[],
                        log=lambda s: None)
    assert doc["baseline"]["exit"] == 0 and doc["baseline"]["unexpected"] == []
    (row,) = doc["mutants"]
    assert row["killed"] and row["claims"] == ["HLW-1.2-d"], row
    assert json.loads((tmp_path / "mutants.json").read_text())["score"] == 1.0
