"""Mutation testing of the ledger (suite/ledger/mutants.py): the catalog is valid, a mutant is
applied to a copy only (never to the installed tree), and the machinery kills one at quick scale.
The full run (every mutant, the whole ledger and the catalog's tests) is the slow command
``gnibench verify --mutants`` (README, "Mutation testing")."""
from __future__ import annotations

import json
import os
import re

import pytest
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.ledger import mutants as M


def test_the_catalog_applies_and_covers_the_asked_categories():
    catalog, settings = M.load_catalog()
    assert len(catalog) >= 25
    problems = [p for p in (M.check(m) for m in catalog) if p]
    assert not problems, problems
    files = {m.file for m in catalog}
    for needed in ("methods/assembly/steps/modifiers.py", "methods/assembly/templates/newton.py",
                   "methods/assembly/templates/fixed.py", "methods/assembly/steps/dense.py",
                   "methods/assembly/steps/partitioned.py", "problems/kepler_ks.py",
                   "suite/cell/reference.py", "suite/metrics/position_in_orbit.py"):
        assert needed in files, needed
    for m in catalog:
        assert m.description and m.plausible, m.id
    for test in settings["tests"]:
        assert (M.package_root() / test).is_file(), test


def test_a_snippet_must_occur_exactly_once(tmp_path):
    copy = M.copy_package(tmp_path)
    twice = M.Mutant("x", "methods/assembly/templates/newton.py", "dnorm", "dnorm2", "d", "p")
    assert "occurs" in M.check(twice, copy)
    with pytest.raises(UserError, match="refusing"):
        M.apply(twice, copy)
    missing = M.Mutant("y", "methods/assembly/templates/newton.py", "no such text", "z", "d", "p")
    assert "occurs 0 times" in M.check(missing, copy)


def test_a_mutant_with_more_edits_changes_every_place(tmp_path):
    """The same bug written twice (the plain step and its compensated twin step_sum) is one
    mutant with further edits; each snippet must occur exactly once."""
    catalog, _ = M.load_catalog()
    m = next(x for x in catalog if x.id == "symplectic-euler-stale-force")
    assert len(m.edits()) == 2
    copy = M.copy_package(tmp_path)
    M.apply(m, copy)
    text = (copy / m.file).read_text()
    assert all(new in text and old not in text for old, new in m.edits())
    bad = M.Mutant("z", m.file, m.original, m.replacement, "d", "p", more=(("dnorm?", "x"),))
    assert "snippet 2 occurs 0 times" in M.check(bad)
    with pytest.raises(UserError, match="pairs"):
        M.load_catalog('[[mutant]]\nid = "a"\nfile = "f"\noriginal = "x"\nreplacement = "y"\n'
                       'description = "d"\nplausible = "p"\nmore = [["only one"]]\n')


def test_compensated_twins_are_mutated_with_their_plain_step():
    """Every mutant of a generator that writes a plain step and a ``step_sum`` twin hits both
    (sum=compensated cells run the twin): the partitioned blocks and Störmer-Verlet's halves."""
    catalog, _ = M.load_catalog()
    twins = {m.id: m for m in catalog if m.file == "methods/assembly/steps/partitioned.py"}
    assert twins and all(len(m.edits()) == 2 for m in twins.values()), list(twins)
    assert all("_sum" in m.more[0][0] or "f(y, par)" in m.more[0][1] for m in twins.values())


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
    written = json.loads((tmp_path / "mutants.json").read_text())
    assert written["score"] == 1.0 and written["complete"] and written["planned"] == 1
    assert written["date"] == doc["date"] and len(written["date"]) == 10


def test_held_out_mutants_from_a_file(tmp_path, capsys):
    """``gnibench verify --mutants FILE.toml``: held-out mutants in the catalog's schema; a bad
    file is one line and exit 2 before any work (nothing written); a file outside the package is
    refused."""
    from gnibench.suite.cli.main import main

    good = ('[[mutant]]\nid = "h"\nfile = "methods/assembly/templates/newton.py"\noriginal = "x"\n'
            'replacement = "y"\ndescription = "d"\nplausible = "p"\n')
    (m,), _ = M.load_catalog(good, "held.toml")
    assert m.id == "h" and m.file == "methods/assembly/templates/newton.py"
    for text, why in [(good.replace('plausible = "p"\n', ""), "missing ['plausible']"),
                      (good + 'severity = 3\n', "unknown keys ['severity']"),
                      ("[[mutant]\n", "not valid TOML"),
                      ("mutant = [1]\n", "bad mutant 1; allowed: [[mutant]] tables")]:
        with pytest.raises(UserError, match=re.escape(why)):
            M.load_catalog(text, "held.toml")
    outside = M.Mutant("o", "../outside.py", "a", "b", "d", "p")
    assert "outside the package" in M.check(outside)
    out = tmp_path / "out"
    (tmp_path / "latin1.toml").write_bytes(b"# \xe9\n")
    for arg, why in [(str(tmp_path / "none.toml"), "no --mutants file"),
                     (str(tmp_path / "latin1.toml"), "is not UTF-8 text"),
                     (str(tmp_path / "empty.toml"), "lists no [[mutant]]")]:
        (tmp_path / "empty.toml").write_text("# nothing\n")
        assert main(["verify", "--mutants", arg, "-o", str(out)]) == 2
        err = capsys.readouterr().err
        assert why in err and len(err.strip().splitlines()) == 1 and not out.exists()
