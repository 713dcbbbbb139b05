"""Mutation testing of the verification (suite/ledger/mutants.py): the catalog is valid, a mutant
is applied to a copy only (never to the installed tree), the tests run against a mutant are those
whose imports reach its file (suite/ledger/importers.py), time limits follow the baseline, and the
machinery kills one at quick scale. The full run (every mutant, the whole ledger and the tests) is
the slow command ``gnibench verify --mutants`` (docs/how-to/mutation-testing.md)."""
from __future__ import annotations

import json
import os
import re

import pytest
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.ledger import mutants as M


@pytest.mark.source_text             # a mutated copy fails it by construction: no kill
def test_the_catalog_applies_and_covers_the_asked_categories():
    catalog, settings = M.load_catalog()
    assert len(catalog) >= 25 and settings == {}
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


def test_a_hand_kept_test_list_is_refused():
    """The tests run against a mutant are computed from the imports, never listed by hand."""
    with pytest.raises(UserError, match=r"unknown top-level keys \['tests'\]"):
        M.load_catalog('tests = ["tests/x.py"]\n', "held.toml")


def test_the_tests_that_see_a_file_are_its_importers_nearest_first():
    """The reverse import graph: a module's own test first, then those reaching it through other
    modules (lazy imports inside functions count); the issue's three missed tests are selected for
    the files they check; a data file is seen by every test; conftest.py is not a test module."""
    from gnibench.suite.ledger import importers as I

    root = M.package_root()
    every = I.all_test_files(root)
    assert len(every) > 50 and "tests/conftest.py" not in every
    assert all(t.startswith("tests/") and "/test_" in t for t in every)
    for file, test in [("suite/cell/reference.py", "tests/cell/test_reference.py"),
                       ("suite/metrics/pericenter.py", "tests/metrics/test_metric_precession.py"),
                       ("methods/scipy_methods.py", "tests/methods/test_scipy_engine.py"),
                       ("suite/runs/store.py", "tests/runs/test_runner_store.py"),
                       ("methods/lie_poisson.py", "tests/methods/test_lie_poisson.py")]:
        seen = I.tests_seeing(root, file)
        assert test in seen, (file, test)
        assert set(seen) <= set(every) and len(seen) < len(every), file
    dist = I.importers(I.import_graph(str(root)), "gnibench.methods.lie_poisson")
    seen = I.tests_seeing(root, "methods/lie_poisson.py")
    assert seen[0] == "tests/methods/test_lie_poisson.py" and dist[seen[0]] == 1
    assert [dist[t] for t in seen] == sorted(dist[t] for t in seen)
    assert I.tests_seeing(root, "suite/claims/b-2.toml") == every
    # a function-local import is an edge (the package imports lazily)
    assert "gnibench.suite.api" in I.import_graph(str(root))["gnibench"]
    assert I.module_of("tests/support.py") == "support"
    assert I.module_of("suite/runs/__init__.py") == "gnibench.suite.runs"


def test_time_limits_kill_only_when_the_baseline_is_fast():
    """A phase may run FACTOR times the baseline's time plus SLACK; an overrun kills only when the
    campaign's cap did not cut that limit (a slow baseline makes a timeout inconclusive)."""
    from gnibench.suite.ledger import mutant_runs as R

    assert R.limit(10.0, 3600.0) == (R.FACTOR * 10.0 + R.SLACK, True)
    assert R.limit(1000.0, 3600.0) == (3600.0, False)
    assert R.limit(None, 3600.0) == (3600.0, False)
    raw = {"rows": [{"id": "a", "unexpected": False}], "exit": 0, "stderr": "",
           "tests_failed": [], "timeouts": [], "inconclusive": ["tests: timed out"]}
    base = {"rows": [{"id": "a", "unexpected": False}]}
    assert not M.judge_mutant(raw, base)["killed"]
    assert M.judge_mutant({**raw, "timeouts": ["tests: timed out"]}, base)["killed"]
    # the ledger not run (a test killed the mutant first) is no crash
    assert not M.judge_mutant({**raw, "exit": None, "rows": [], "inconclusive": []}, base)["killed"]
    files = ["tests/a.py", "tests/b.py"]
    assert R.estimate(files, {"tests/a.py": 40.0, "tests/b.py": 20.0}, 2) == 30.0 + R.PYTEST_START
    assert R.estimate(files, {}, 2) is None
    assert R.tiers(["x", "y", "z"], {"x": 1, "y": 2, "z": 5}) == [["x"], ["y"], ["z"]]
    assert R.tiers(list("abcdef"), dict(zip("abcdef", range(1, 7))), most=3) == [
        ["a"], ["b"], ["c", "d", "e", "f"]]


def test_a_test_that_sees_the_mutant_kills_it(tmp_path):
    """A mutant of a metric that the chosen claim does not read survives the ledger and is killed
    by a test module whose imports reach the metric; the failing test passes on the baseline's
    copy (the kill is confirmed there)."""
    bug = M.Mutant("final-is-max", "suite/metrics/global_error.py",
                   '"final_global_error": float(g[-1])', '"final_global_error": float(np.max(g))',
                   "final = max", "p")
    doc = M.run_mutants([bug], tmp_path, scale="quick", jobs=1, claims=["HLW-1.2-d"],
                        tests=["tests/metrics/test_metric_meanings.py"], log=lambda s: None)
    (row,) = doc["mutants"]
    assert row["killed"] and row["tests"] and not row["claims"], row
    assert row["tests"][0].startswith("tests/metrics/test_metric_meanings.py::"), row["tests"]
    assert doc["baseline"]["tests_failing"] == []
    # the test reaches the metric through suite/metrics/compute.py (distance 2): the ledger runs
    # first, does not kill it, and the test phase does
    assert [p["phase"] for p in row["phases"]] == ["ledger", "tests (1 files)"]
