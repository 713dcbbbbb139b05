"""The claims ledger: entries as data, the expression language, the closed forms against runs and
brute force, identity checks, and `gnibench verify` end to end on a few claims."""
from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import pytest
from gnibench.suite.cli.main import main
from gnibench.suite.foundation import expressions
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.ledger import closed_forms, entries, identities
from gnibench.suite.ledger.entries import load_ledger, parse_claims
from gnibench.suite.ledger.verdicts import select



def test_every_shipped_claim_validates_and_checks_exist():
    ledger = load_ledger()
    assert ledger
    for c in ledger.values():
        if c.check:
            assert c.check in identities.names(), c.id
        if c.closed_form:
            assert c.closed_form in closed_forms.CLOSED_FORMS, c.id


def _inventory() -> list[str]:
    from importlib import resources

    text = (resources.files("gnibench.suite") / "claims" / "inventory.txt").read_text()
    return [line for line in text.splitlines() if line and not line.startswith("#")]


def test_the_ledger_covers_the_inventory_exactly():
    """One entry per claim of the seeds' inventory (suite/claims/inventory.txt, 132), no more, no less — besides the corrected relations
    of the seeds' slips, ``<id>.corrected``, each beside the entry of its printed claim."""
    inventory, ledger = _inventory(), load_ledger()
    assert len(inventory) == len(set(inventory)) == 132
    missing = [i for i in inventory if i not in ledger]
    corrected = [i for i in ledger if i.endswith(".corrected")]
    extra = [i for i in ledger if i not in inventory and i not in corrected]
    assert not missing and not extra, f"missing {missing}, not in the inventory {extra}"
    orphans = [i for i in corrected if i.removesuffix(".corrected") not in inventory]
    assert not orphans, f"corrected entries without their printed claim: {orphans}"
    assert corrected, "the policy on slips: at least the slips of the claims inventory Part 4 are corrected"


@pytest.mark.parametrize("text,ok", [
    ("measured >= 1e6", True), ("abs(a - b) / max(a, 1e-300) <= 0.05 and c > 0", True),
    ("log10(x) + 2 ** 3", True), ("__import__('os')", False), ("a.b", False), ("[1, 2]", False),
    ("open('x')", False), ("'text'", False),
])
def test_expressions_accept_arithmetic_only(text, ok):
    if ok:
        expressions.parse(text, "t")
    else:
        with pytest.raises(UserError, match="allowed"):
            expressions.parse(text, "t")


def test_expressions_evaluate():
    tree = expressions.parse("a / b >= 1e6 and 0 < c < 1", "t")
    assert expressions.evaluate(tree, {"a": 2e6, "b": 1.0, "c": 0.5}) is True
    assert expressions.evaluate(tree, {"a": math.nan, "b": 1.0, "c": 0.5}) is False
    assert expressions.evaluate(expressions.parse("x / 0", "t"), {"x": 1.0}) == math.inf


BAD_ENTRIES = {
    "no way": ('id = "B-9-a"\nkind = "E"\ncitation = "c"\nclaim = "x"', "exactly one of"),
    "two ways": (('id = "B-9-a"\nkind = "I"\ncitation = "c"\nclaim = "x"\ncheck = "arithmetic"\n'
                 'not_checkable = "y"\npasses = "1 > 0"'), "exactly one of"),
    "unknown name": (('id = "B-9-a"\nkind = "E"\ncitation = "c"\nclaim = "x"\nexperiment = "e"\n'
                     'values.a = {cells = "", column = "x"}\nmeasured = "a + b"\npasses = "1 > 0"'),
                     "unknown names"),
    "bad expected": (('id = "B-9-a"\nkind = "I"\ncitation = "c"\nclaim = "x"\ncheck = "arithmetic"\n'
                     'passes = "1 > 0"\nexpected = "maybe"'), "bad expected"),
    "bad id": (('id = "X-1"\nkind = "I"\ncitation = "c"\nclaim = "x"\ncheck = "arithmetic"\n'
               'passes = "1 > 0"'), "bad id"),
}


@pytest.mark.parametrize("case", sorted(BAD_ENTRIES))
def test_bad_entries_are_refused(case):
    body, message = BAD_ENTRIES[case]
    with pytest.raises(UserError, match=message):
        parse_claims(f"[[claim]]\n{body}\n", "x.toml")


def test_selector():
    cells = pd.DataFrame({"cell": [0, 1, 2], "label": ["Euler h=0.1", "Euler h=0.1 + obs", "RK"],
                          "method": ["euler:h=0.1", "euler:h=0.1+observer", "rk4"]})
    assert select(cells, "label=Euler h=0.1")["cell"].tolist() == [0]
    assert select(cells, "label~Euler & method~observer")["cell"].tolist() == [1]
    assert select(cells, "")["cell"].tolist() == [0, 1, 2]


def test_observer_limit_is_the_fixed_point_of_the_map():
    """R(h, θ) of the closed form against iterating the energy map by brute force."""
    for h, theta in ((0.01, 10.0), (0.1, 15.0), (0.001, 1000.0)):
        R, slope = closed_forms.observer_limit(h, theta, 0.5)
        H = 0.5
        for _ in range(200000):
            H = H * ((1 + h * theta * (0.5 - H) / (2 * H)) ** 2 + h * h)
        assert slope < 1 and abs(H - R) <= 1e-14 and R > 0.5
    assert closed_forms.observer_limit(0.1, 0.001, 0.5)[0] == math.inf     # no fixed point


def test_energy_recurrence_matches_euler_runs():
    from gnibench.suite.cell.solve import solve
    from gnibench.suite.metrics.compute import apply
    from gnibench.suite.runs.tables import sample_frame

    rows, frames = [], []
    specs = [("double-oscillator", "euler:h=0.01"),
             ("double-oscillator", "euler:h=0.01+observer:on=H2,theta=50"),
             ("harmonic-oscillator", "euler:h=0.05+observer:theta=3")]
    for i, (p, m) in enumerate(specs):
        t = solve(p, m, steps=3000, every=100)
        out, _ = apply(t)
        f = sample_frame(t, out)
        f.insert(0, "cell", i)
        frames.append(f)
        rows.append({"cell": i, "problem": t.problem, "problem_id": p, "method": t.method})
    got = closed_forms.euler_oscillator_energy(pd.DataFrame(rows), pd.concat(frames))
    assert got["deviation"] <= 1e-12
    # a wrong step size in the recurrence is caught
    rows[0]["method"] = rows[0]["method"].replace("h=0.01", "h=0.0101")
    assert closed_forms.euler_oscillator_energy(pd.DataFrame(rows[:1]), frames[0])["deviation"] > 1e-3


def test_main_lemma_decay_on_a_synthetic_exponential():
    t = np.linspace(0, 10, 101)
    cells = pd.DataFrame([{"cell": 0, "problem": "harmonic-oscillator",
                           "method": "rk4:h=0.01+observer:mode=simple,on=H,theta=2,H0=0.6"}])
    eps = 0.1 * np.exp(-2 * t)                                   # ε = H0 − H
    samples = pd.DataFrame({"cell": 0, "t": t, "err_H": 0.6 - eps - 0.5})
    got = closed_forms.main_lemma_decay(cells, samples)
    assert got["slope_error"] < 1e-9 and got["violation"] <= 1e-12
    samples["err_H"] = 0.6 - 0.1 * np.exp(-1.5 * t) - 0.5       # too slow: violates (2.8)
    got = closed_forms.main_lemma_decay(cells, samples)
    assert got["slope_error"] > 0.2 and got["violation"] > 1.0


@pytest.mark.parametrize("name", ["arithmetic", "so4_manakov", "genus2_R0", "genus2_curvature",
                                  "gs_canonical_transform", "gs_equilibrium_types",
                                  "kepler_eccentricity_relation", "henon_heiles_saddles",
                                  "imr_symmetric", "penalty_indefinite"])
def test_identity_checks_run(name):
    assert isinstance(identities.run(name), dict)


def test_verify_a_few_claims(tmp_path, capsys):
    out = tmp_path / "v"
    code = main(["verify", "B-4.2-d", "B-3-b", "HLW-3-a", "-o", str(out), "-j", "1",
                 "--format", "json"])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    rows = {r["id"]: r for r in json.loads(captured.out)}
    assert set(rows) == {"B-4.2-d", "B-3-b", "HLW-3-a"}
    for r in rows.values():
        assert {"id", "citation", "verdict", "expected", "measured", "seed_value"} <= set(r)
    assert rows["B-4.2-d"]["verdict"] == "reproduced" and rows["B-4.2-d"]["measured"] > 1
    assert rows["B-3-b"]["verdict"] == rows["B-3-b"]["expected"] == "not reproduced"
    assert abs(rows["B-3-b"]["measured"] - math.exp(0.69)) < 1e-12
    table = pd.read_parquet(out / "ledger.parquet")
    assert len(table) == 3 and (out / "ledger.md").is_file()
    page = (out / "report" / "ledger-v.html").read_text()     # the report site, by default
    assert '<tr id="B-3-b">' in page and 'class="badge verdict not-reproduced">not reproduced' in page
    assert "1 not reproduced" in (out / "report" / "index.html").read_text()


def test_an_unexpected_verdict_sets_the_exit_code(tmp_path, capsys, monkeypatch):
    """A known failure that starts to pass is reported: exit 1."""
    real = entries.shipped_files

    def files():
        return {**real(), "zz.toml": '[[claim]]\nid = "B-9-z"\nkind = "I"\ncitation = "test"\n'
                                     'claim = "<script>alert(1)</script> | # fake"\n'
                                     'check = "arithmetic"\nmeasured = "2"\n'
                                     'passes = "measured > 1"\nexpected = "not reproduced"\n'}

    monkeypatch.setattr(entries, "shipped_files", files)
    out = tmp_path / "v"
    assert main(["verify", "B-9-z", "-o", str(out)]) == 1
    assert "UNEXPECTED" in capsys.readouterr().out
    md = (out / "ledger.md").read_text()
    assert "<script>" not in md and "&lt;script&gt;" in md and "\\| # fake" in md


def test_list_and_bad_input(capsys):
    assert main(["verify", "--list"]) == 0
    assert "B-4.2-d" in capsys.readouterr().out
    assert main(["verify", "B-4.2-x"]) == 2
    assert "did you mean" in capsys.readouterr().err
    assert main(["verify", "--scale", "huge"]) == 2


def test_one_sided_criteria_say_why():
    """Every entry whose pass criterion bounds a measured number on one side only says why in
    ``one_sided`` (the seed gives no other side), and no two-sided entry carries a stale reason
    (issue 41). The detector itself: both sides, abs(), equalities and orders are two-sided."""
    from gnibench.suite.ledger.entries import load_ledger
    from gnibench.suite.ledger.sides import one_sided_terms

    assert one_sided_terms("measured >= 10") == ["measured"]
    assert one_sided_terms("0.1 <= measured <= 10") == []
    assert one_sided_terms("x >= 1 and x <= 2 and abs(a - 1) <= 0.2 and n == 3") == []
    assert one_sided_terms("ee2 < ee1 and ee1 < 0 and g >= 0.1") == ["g"]
    assert one_sided_terms("measured >= 2 and exp(0.69) < 2") == ["measured"]
    missing, stale = [], []
    for c in load_ledger().values():
        terms = one_sided_terms(c.passes)
        if terms and not c.one_sided:
            missing.append(f"{c.id}: {terms}")
        if c.one_sided and not terms:
            stale.append(c.id)
    assert not missing and not stale, (missing, stale)
