"""The ledger judges only what ran: failed and truncated runs, values at times a run did not reach,
broken entries (the verdict ``error``), method swaps, the §6 chaos measure, HLW-2.4-b's
certificate, and the fixed-point implicit Euler."""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from gnibench.suite.cli.main import main
from gnibench.suite.ledger import entries, verdicts
from gnibench.suite.ledger.closed_forms_b6 import SAMPLING_BOUND, chaos_stats
from gnibench.suite.ledger.entries import parse_claims
from gnibench.suite.ledger.verdicts import Results, evaluate


def _tables(status="ok", t_final=10.0, steps=1000, section=0, samples=11):
    cells = pd.DataFrame([{"cell": 0, "group": 0, "label": "run", "problem": "p", "method": "m",
                           "t_end": 10.0, "steps_planned": 1000, "status": status,
                           "reason": "" if status == "ok" else "it broke", "t_final": t_final,
                           "steps": steps, "section": section, "samples": samples,
                           "max_abs_err_H": 1e-9}])
    t = np.linspace(0, t_final, samples)
    samp = pd.DataFrame({"cell": 0, "t": t, "steps": np.linspace(0, steps, samples),
                         "err_H": 1e-10 * t})
    return cells, samp


class _Fake(Results):
    def __init__(self, tables):
        super().__init__({})
        self._tables = {"exp": tables}


def _claim(body: str):
    text = ('[[claim]]\nid = "B-9-z"\nkind = "E"\ncitation = "test"\nclaim = "x"\n'
            'experiment = "exp"\n' + body)
    return parse_claims(text, "t.toml")[0]


COLUMN = 'values.e = {cells = "", column = "max_abs_err_H"}\nmeasured = "e"\npasses = "e < 1"\n'


@pytest.mark.parametrize("status", ["nonfinite", "newton_failed", "max_steps", "step_too_small",
                                    "error", "pending"])
def test_a_failed_run_never_gives_reproduced(status):
    v = evaluate(_claim(COLUMN), _Fake(_tables(status=status, t_final=4.0)), {})
    assert v.verdict == "not reproduced" and v.outcome == "not measured"
    assert status in v.detail and "cell 0" in v.detail
    assert v.runs and v.runs[0].status == status
    row = v.row()
    assert not row["runs_complete"] and status in row["runs"]


def test_a_complete_run_is_judged():
    v = evaluate(_claim(COLUMN), _Fake(_tables()), {})
    assert v.verdict == "reproduced" and v.runs[0].reach().startswith("t = 10")


def test_a_value_at_a_time_the_run_did_not_reach_is_not_measured():
    """A complete run with a shorter horizon (the quick scale) gives no value at t = 20, where the
    old lookup returned the last sample before it silently."""
    body = 'values.e = {cells = "", sample = "err_H", at = "t=20"}\nmeasured = "e"\npasses = "e < 1"\n'
    v = evaluate(_claim(body), _Fake(_tables()), {})
    assert v.outcome == "not measured" and "t=20 was not reached" in v.detail
    body = body.replace("t=20", "t=5")
    assert evaluate(_claim(body), _Fake(_tables()), {}).verdict == "reproduced"
    off_grid = evaluate(_claim(body.replace("t=5", "t=5.5")), _Fake(_tables()), {})
    assert off_grid.outcome == "not measured" and "nearest before is at t=5" in off_grid.detail
    body = body.replace("t=5", "steps=2000")
    assert evaluate(_claim(body), _Fake(_tables()), {}).outcome == "not measured"
    assert evaluate(_claim(body.replace("steps=2000", "steps=550")), _Fake(_tables()),
                    {}).outcome == "not measured"            # samples every 100 steps


def test_a_section_run_short_of_its_points_is_truncated_unless_the_horizon_is_the_ask():
    tables = _tables(section=500, samples=395)
    assert evaluate(_claim(COLUMN), _Fake(tables), {}).outcome == "not measured"
    v = evaluate(_claim(COLUMN + 'reach = "horizon"\n'), _Fake(tables), {})
    assert v.verdict == "reproduced"


def test_accept_names_the_failures_that_are_the_claim():
    body = COLUMN.replace('column = "max_abs_err_H"', 'column = "max_abs_err_H", accept = ["step_too_small"]')
    assert evaluate(_claim(body), _Fake(_tables("step_too_small", 4.0)), {}).verdict == "reproduced"
    assert evaluate(_claim(body), _Fake(_tables("nonfinite", 4.0)), {}).outcome == "not measured"


@pytest.mark.parametrize("body", [
    'values.e = {cells = "", column = "max_abs_err_Q"}\nmeasured = "e"\npasses = "e < 1"\n',
    'values.e = {cells = "label=nobody", column = "max_abs_err_H"}\nmeasured = "e"\npasses = "e < 1"\n',
    'values.e = {cells = "lable=run", column = "max_abs_err_H"}\nmeasured = "e"\npasses = "e < 1"\n',
    'values.e = {cells = "", sample = "err_Q", at = "last"}\nmeasured = "e"\npasses = "e < 1"\n',
    'closed_form = "no_such_form"\ncells = ""\npasses = "x < 1"\n',
    'closed_form = "gs_section_trace"\ncells = ""\npasses = "w < 1"\n',
])
def test_a_broken_entry_is_an_error_and_always_unexpected(body):
    v = evaluate(_claim(body), _Fake(_tables()), {})
    assert v.verdict == "error" and v.unexpected and "measurement failed" in v.detail


def test_a_broken_entry_exits_1(tmp_path, capsys, monkeypatch):
    real = entries.shipped_files
    bad = ('[[claim]]\nid = "B-9-z"\nkind = "E"\ncitation = "t"\nclaim = "x"\n'
           'experiment = "ledger-b-4.2"\nvalues.e = {cells = "label=Euler h=0.1", '
           'column = "max_abs_err_H9"}\nmeasured = "e"\npasses = "e > 0"\n')
    monkeypatch.setattr(entries, "shipped_files", lambda: {**real(), "zz.toml": bad})
    assert main(["verify", "B-9-z", "-o", str(tmp_path / "v"), "--no-report"]) == 1
    captured = capsys.readouterr()
    assert "error" in captured.out and "UNEXPECTED" in captured.out
    assert "no column 'max_abs_err_H9'" in captured.out          # why, on the console too
    assert "regression record" in captured.err


@pytest.mark.parametrize("body", [
    'values.e = {cells = "", column = "max_abs_err_Q"}\nmeasured = "e"\npasses = "e < 1"\n',
    'values.e = {cells = "", sample = "err_Q", at = "last"}\nmeasured = "e"\npasses = "e < 1"\n',
    'values.e = {cells = "", sample = "err_H", at = "stpes=5"}\nmeasured = "e"\npasses = "e < 1"\n',
    'values.e = {cells = "", column = "max_abs_err_H"}\nmeasured = "e"\npasses = "ee < 1"\n',
    'values.e = {cells = "", column = "max_abs_err_H"}\nmeasured = "e"\npasses = "e < 1"\n'
    'partly = "e < 1 and x > 0"\n',
    'values.e = {cells = "", column = "max_abs_err_H"}\nmeasured = "e"\npasses = "e < 1"\n'
    'sweep = "problem"\npartly = "f < 2"\n',
    'closed_form = "no_such_form"\ncells = ""\npasses = "x < 1"\n',
    'not_checkable = "a swap"\nside.e = {cells = "", column = "max_abs_err_Q"}\n',
])
def test_a_typo_is_an_error_even_behind_a_run_that_did_not_complete(body):
    """The names are checked before the runs' status: a failed run must not hide a typo behind
    "not measured" (where an entry expects "not measured", the typo would never be noticed)."""
    v = evaluate(_claim(body), _Fake(_tables("nonfinite", 4.0)), {})
    assert v.verdict == "error" and v.unexpected, v.detail


def test_runs_complete_follows_the_entrys_reach():
    """A section run that reached its horizon with fewer points than its cap is complete under
    reach = "horizon" (so(4), [B] §7.2), in the table as in the verdict; an accepted failure is
    judged but its run is not complete; an aggregate's runs are complete when its parts' are."""
    tables = _tables(section=500, samples=395)
    horizon = evaluate(_claim(COLUMN + 'reach = "horizon"\n'), _Fake(tables), {})
    assert horizon.verdict == "reproduced" and horizon.row()["runs_complete"]
    assert not evaluate(_claim(COLUMN), _Fake(tables), {}).row()["runs_complete"]
    body = COLUMN.replace('column = "max_abs_err_H"',
                          'column = "max_abs_err_H", accept = ["step_too_small"]')
    accepted = evaluate(_claim(body), _Fake(_tables("step_too_small", 4.0)), {})
    assert accepted.verdict == "reproduced" and not accepted.row()["runs_complete"]
    agg = parse_claims('[[claim]]\nid = "B-9-y"\nkind = "E"\ncitation = "t"\nclaim = "x"\n'
                       'all_of = ["B-9-z"]\n', "t.toml")[0]
    assert evaluate(agg, _Fake(tables), {"B-9-z": horizon}).row()["runs_complete"]
    assert not evaluate(agg, _Fake(tables), {"B-9-z": accepted}).row()["runs_complete"]


def test_a_near_miss_is_shown_in_percent():
    """1.994 against ≥ 2 (B-3-b as printed) is off by 0.3 %, not "×1"."""
    from gnibench.suite.ledger import misses

    assert "(off by 0.3 %)" in misses.describe(misses.failing("m >= 2", {"m": 1.994}))
    assert "(off by ×4)" in misses.describe(misses.failing("m >= 2", {"m": 0.5}))


def test_not_checkable_only_for_entries_that_say_why():
    v = evaluate(_claim('not_checkable = "a method swap"\nexpected = "not checkable"\n'),
                 _Fake(_tables()), {})
    assert v.verdict == "not checkable" and not v.unexpected
    side = ('not_checkable = "a method swap"\nexpected = "not checkable"\n'
            'side.e = {cells = "", column = "max_abs_err_H"}\n')
    v = evaluate(_claim(side), _Fake(_tables()), {})
    assert v.verdict == "not checkable" and "side result: e = 1e-09" in v.measured


def test_paper_only_claims_are_skipped_at_the_quick_scale():
    v = evaluate(_claim(COLUMN + 'scale = "paper"\n'), _Fake(_tables()), {}, scale="quick")
    assert v.verdict == "skipped" and not v.unexpected


def test_sweep_reports_the_closest_point_and_what_fails():
    cells = pd.DataFrame([{"cell": k, "label": "run", "problem": f"p{k}", "status": "ok",
                           "t_final": 1.0, "t_end": 1.0, "steps": 10, "steps_planned": 10,
                           "section": 0, "samples": 2, "e": e} for k, e in enumerate((1e-3, 1e-5))])
    body = ('values.e = {cells = "", column = "e"}\nmeasured = "e"\npasses = "e <= 1e-8"\n'
            'sweep = "problem"\n')
    v = evaluate(_claim(body), _Fake((cells, pd.DataFrame({"cell": [0]}))), {})
    assert v.verdict == "not reproduced" and v.closest.startswith("problem p1")
    assert "off by ×1e+03" in v.closest
    # partly: the closest is the nearest point that fails, with what fails there
    v = evaluate(_claim(body.replace("1e-8", "1e-4")), _Fake((cells, pd.DataFrame({"cell": [0]}))),
                 {})
    assert v.verdict == "partly" and v.closest.startswith("problem p0") and "e = 0.001" in v.failing


def test_the_ledger_page_shows_runs_and_never_presents_agreement_as_evidence():
    from gnibench.reports.ledger import ledger_context, render_ledger

    v = evaluate(_claim(COLUMN), _Fake(_tables("nonfinite", 4.0)), {})
    table = pd.DataFrame([v.row()])
    md = render_ledger(table, {"scale": "quick"})
    assert "regression record" in md and "not evidence" in md and "nonfinite" in md
    ctx = ledger_context(table, {"scale": "quick"}, set())
    row = ctx["sections"][0]["rows"][0]
    assert row["not_measured"] and "stopped at" in " ".join(x for _, x in row["extra"])
    assert row["runs"] and "t = 4 of 10" in row["runs"][0]


def test_chaos_measure_regular_and_irregular_passages():
    """A passage sampled on its own level stays within the sampling bound; one that turns away
    off its level (the level changed during the passage) is irregular."""
    rows = pd.DataFrame({"q1": [0.0] * 3, "q2": [0.0] * 3, "p1": [0.0] * 3, "p2": [1e-4, 2e-4, 3e-4]})
    # (q2, p2) = (0, r) with q1 = p1 = 0: E = −r²/2 + r⁴/4, I = 0: d_min² = 2|E| ≈ r², ρ ≈ 0
    r = np.hypot(rows["q2"], rows["p2"]).to_numpy()
    stats = chaos_stats("gavrilov-shilnikov", rows, r, [(0, 3)])
    assert stats["passages"] == 1 and stats["rho_max"] < 1e-6 and stats["irregular"] == 0
    off = rows.assign(q2=[3e-4, 3e-4, 3e-4])       # on a level with a much closer minimum
    r = np.hypot(off["q2"], off["p2"]).to_numpy()
    assert chaos_stats("gavrilov-shilnikov", off, r, [(0, 3)])["rho_max"] > SAMPLING_BOUND
    assert abs(SAMPLING_BOUND - 0.5 * math.log10(math.cosh(1.0))) < 1e-15


def test_implicit_euler_gap_certificate():
    """[HLW] I.2.4: no solution of the implicit Euler step when the predicted position is inside
    (3/2)(2c)^{1/3}; a solution (margin < 0) far from the sun."""
    from gnibench.suite.ledger.closed_forms_hlw import _implicit_euler_gap

    values = {"G": 2.95912208286e-4, "m0": 1.0, **{f"m{k}": 1e-4 for k in range(1, 6)}}

    def rows(r_j):
        d = {f"{c}{k}{x}": [0.0] for c in "qp" for k in range(6) for x in "xyz"}
        d["q1x"], d["t"] = [r_j], [0.0]
        for k in range(2, 6):
            d[f"q{k}x"] = [10.0 * k]
        return pd.DataFrame(d)

    near = _implicit_euler_gap(rows(0.3), values, 10.0)
    far = _implicit_euler_gap(rows(5.0), values, 10.0)
    assert near["margin"] > 0 > far["margin"]
    assert abs(near["g_min"] - 1.5 * (2 * 100 * values["G"] * (1 + 1e-4)) ** (1 / 3)) < 1e-15


def test_fixed_point_implicit_euler():
    """Converged: the same map as Newton's to round-off; not converged: accepted, counted in njev,
    status ok."""
    from gnibench.suite.cell.solve import solve

    newton = solve("harmonic-oscillator", "implicit-euler:h=0.01", steps=200, every=200)
    fixed = solve("harmonic-oscillator", "implicit-euler:h=0.01,fixed_point=100", steps=200,
                  every=200)
    assert np.max(np.abs(newton.y - fixed.y)) < 1e-13 and fixed.njev[-1] == 0
    rough = solve("harmonic-oscillator", "implicit-euler:h=0.01,fixed_point=2", steps=200,
                  every=200)
    assert str(rough.status) == "ok" and rough.njev[-1] == 200
    assert np.max(np.abs(newton.y - rough.y)) > 1e-9


def test_verdict_order_counts_every_verdict():
    assert set(verdicts.VERDICT_ORDER) >= {"reproduced", "partly", "not reproduced",
                                           "not checkable", "skipped", "error"}


def test_the_ledger_page_shows_the_mutation_score_and_the_survivors(tmp_path):
    import json

    from gnibench.reports.ledger import ledger_context, mutation_summary, render_ledger

    doc = {"scale": "quick", "score": 0.5, "mutants": [
        {"id": "a", "file": "f.py", "description": "bug a", "killed": True, "claims": ["B-4.2-d"],
         "tests": []},
        {"id": "b", "file": "g.py", "description": "bug b", "killed": False, "claims": [],
         "tests": [], "blind_spot": "no claim reads it"}]}
    (tmp_path / "mutants.json").write_text(json.dumps(doc))
    summary = mutation_summary(tmp_path)
    assert summary["killed"] == 1 and summary["total"] == 2
    v = evaluate(_claim(COLUMN), _Fake(_tables()), {})
    md = render_ledger(pd.DataFrame([v.row()]), {"scale": "quick"}, summary)
    assert "1 of 2 mutants" in md and "survived: `b`" in md and "no claim reads it" in md
    assert ledger_context(pd.DataFrame([v.row()]), {}, set(), summary)["mutants"]["total"] == 2
    assert mutation_summary(tmp_path / "nowhere") is None
    doc.update(date="2031-01-02", planned=5)          # an interrupted campaign says so
    (tmp_path / "mutants.json").write_text(json.dumps(doc))
    md = render_ledger(pd.DataFrame([v.row()]), {"scale": "quick"}, mutation_summary(tmp_path))
    assert "quick scale, 2031-01-02" in md and "3 of the 5 mutants" in md



def test_many_values_are_summarised_on_the_page_and_kept_in_the_table(monkeypatch):
    """A closed form with more than SHOWN_VALUES named values (the §6 statistics of several
    cells: 100+) shows on the page and in ledger.md the values its verdict reads; ledger.parquet's
    ``values`` keeps them all. A closed form with few values shows them all."""
    from gnibench.reports.ledger import ledger_context, render_ledger
    from gnibench.suite.ledger import closed_forms

    many = {f"v{k}": float(k) for k in range(40)}
    monkeypatch.setitem(closed_forms.CLOSED_FORMS, "many", lambda cells, samples: dict(many))
    monkeypatch.setitem(closed_forms.CLOSED_FORMS, "few",
                        lambda cells, samples: {k: many[k] for k in ("v1", "v2", "v3")})
    body = 'closed_form = "{}"\nmeasured = "v7"\npasses = "v3 < 4 and v7 < 8"\npartly = "v1 < 2"\n'
    v = evaluate(_claim(body.format("many")), _Fake(_tables()), {})
    assert v.verdict == "reproduced" and v.measured == 7.0
    assert v.detail == "v1 = 1, v3 = 3, v7 = 7; 37 more values in ledger.parquet (column values)"
    row = v.row()
    assert all(f"v{k} = {k}," in row["values"] + "," for k in range(40))
    table = pd.DataFrame([row])
    md = render_ledger(table, {"scale": "quick"})
    assert "v7 = 7" in md and "v12 = 12" not in md and "37 more values" in md
    extra = " ".join(x for _, x in ledger_context(table, {"scale": "quick"}, set())
                     ["sections"][0]["rows"][0]["extra"])
    assert "v3 = 3" in extra and "v20 = 20" not in extra
    few = evaluate(_claim(body.format("few").replace("v7", "v2").replace("< 8", "< 3")),
                   _Fake(_tables()), {})
    assert few.detail == "v1 = 1, v2 = 2, v3 = 3" == few.row()["values"]
