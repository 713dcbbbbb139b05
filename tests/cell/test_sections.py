"""Poincaré sections (suite/cell/sections.py): crossings located to <= 1e-13 by dense output (dopri5,
dop853 adaptive) or by Hénon's trick (every other cell).

The harmonic oscillator q' = p, p' = -q from (q, p) = (0, 1) is (sin t, cos t): it crosses
{q = 0, p > 0} at t = 2 pi k with p = 1. The test gives it a temporary section (a new id, so its
generated code has the section functions). What is located is the crossing of the NUMERICAL orbit:
the located point must be on the section (|q| <= 1e-13) and on the exact flow through the sample
before it; only for a method with tiny global error is it also the exact crossing (2 pi k, p = 1).
"""
from __future__ import annotations

import io
import math

import numpy as np
import pandas as pd
import pytest
from gnibench.problems import REGISTRY
from gnibench.suite.cell.sections import crossing_intervals
from gnibench.suite.cell.solve import solve
from gnibench.suite.cli.main import main
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.metrics.compute import apply
from gnibench.suite.metrics.global_error import global_errors
from gnibench.suite.runs.tables import sample_frame

OSC_ID = "harmonic-oscillator-sec-test"
P = f"{OSC_ID}:q0=0,p0=1"
TOL = 1e-13


@pytest.fixture
def osc(monkeypatch):
    from support import section_oscillator   # here: a subprocess imports this module too

    return section_oscillator(monkeypatch, OSC_ID)



def solve_section(problem: str, method: str, crossings: int, **kw):
    """The section crossings of a cell, as ``gnibench solve --section`` computes them."""
    return solve(problem, method, section=crossings, **kw)


def columns(r) -> dict:
    """The columns of a section table, as ``gnibench solve --section`` writes them."""
    out, _ = apply(r)
    return {c: v.to_numpy() for c, v in sample_frame(r, out).items()}

def test_crossing_intervals_half_open():
    # a sample exactly on the section belongs to the interval ending there; t = 0 is never one
    assert crossing_intervals(np.array([0.0, -1.0, 1.0, 0.0, -2.0, -1.0])).tolist() == [1, 2]
    assert crossing_intervals(np.array([1.0, 0.0, 1.0])).tolist() == [0]


def test_exact_crossings_with_small_error(osc):
    """rk4 with h = 5e-4 (global error ~1e-15 here): the crossings are t = 2 pi k, p = 1."""
    r = solve_section(P, "rk4:h=0.0005", 3, t_end=25.0)
    c = columns(r)
    assert r.status == "ok" and r.reason == ""
    assert c["crossing"].tolist() == [1, 2, 3]
    assert np.max(np.abs(c["q"])) <= TOL
    assert np.max(np.abs(c["t"] - 2 * math.pi * np.arange(1, 4))) <= 1e-13
    assert np.max(np.abs(c["p"] - 1.0)) <= 1e-13
    assert list(c) == ["crossing", "t", "p", "q", "err_H"]
    assert np.max(np.abs(c["err_H"] - ((c["p"] ** 2 + c["q"] ** 2) / 2 - 0.5))) <= 1e-15
    assert r.provenance["max_abs_g"] <= TOL


def test_crossing_is_on_the_numerical_orbit(osc):
    """rk4 with h = 0.1: the orbit is 1e-5 off the exact one; the located point is on the section
    and on the exact flow through the sample before the crossing (not the exact crossing)."""
    h = 0.1
    r = solve_section(P, f"rk4:h={h}", 3, t_end=25.0)
    c = columns(r)
    assert np.max(np.abs(c["q"])) <= TOL
    assert np.max(np.abs(c["t"] - 2 * math.pi * np.arange(1, 4))) > 1e-7     # numerical, not exact
    traj = solve(P, f"rk4:h={h}", t_end=25.0)
    for k in range(3):
        ts, ys = c["t"][k], np.array([c["q"][k], c["p"][k]])
        n = math.floor(ts / h)
        assert traj.t[n] <= ts <= traj.t[n + 1]
        assert traj.y[n, 0] * traj.y[n + 1, 0] < 0
        flow = osc.exact(np.array([ts - traj.t[n]]), traj.y[n], {})[0]
        assert np.max(np.abs(flow - ys)) <= TOL


@pytest.mark.parametrize("method", ["rkf45:rtol=1e-6,atol=1e-6", "odex:rtol=1e-5,atol=1e-5",
                                    "gauss4:h=0.2"])
def test_henon_point_is_on_the_exact_flow_from_the_accepted_point(osc, method):
    """Adaptive, extrapolation and implicit cells far from the exact orbit (1e-6 .. 1e-4): the
    point located inside the compiled driver is on the exact flow through the accepted point
    before the crossing, to round-off, at the located time. odex's steps (~1.8) hold the maximum
    of q before a downward crossing: Hénon's trick from the step's start would run backward to
    the previous (upward) crossing and count it twice; the flow is first carried in time past the
    turning point (``time_walks``)."""
    r = solve_section(P, method, 3, t_end=25.0)
    traj = solve(P, method, t_end=25.0)
    assert r.provenance["henon"]["not_located"] == 0
    assert (r.provenance["henon"]["time_walks"] > 0) == method.startswith("odex")
    assert np.max(np.abs(r.t - 2 * math.pi * np.arange(1, 4))) > 1e-9     # numerical, not exact
    for k in range(3):
        n = int(np.searchsorted(traj.t, r.t[k])) - 1
        assert traj.y[n, 0] < 0 <= traj.y[n + 1, 0] and r.steps[k] == traj.steps[n + 1]
        flow = osc.exact(np.array([r.t[k] - traj.t[n]]), traj.y[n], {})[0]
        assert np.max(np.abs(flow - r.y[k])) <= TOL


def test_same_method_step_reproduces_the_point(osc):
    """One rk4 step of the gap t* - t_n from the sample y_n lands on the located point."""
    h = 1e-3
    r = solve_section(P, f"rk4:h={h}", 1, t_end=7.0)
    ts, ys = columns(r)["t"][0], np.array([columns(r)["q"][0], columns(r)["p"][0]])
    traj = solve(P, f"rk4:h={h}", t_end=7.0)
    n = math.floor(ts / h)
    q0, p0 = (float(x) for x in traj.y[n])
    step = solve(f"{OSC_ID}:q0={q0!r},p0={p0!r}", f"rk4:h={float(ts - traj.t[n])!r}", steps=1)
    assert np.max(np.abs(step.y[-1] - ys)) <= TOL


@pytest.mark.parametrize("method", ["dop853:rtol=1e-12,atol=1e-12",      # adaptive driver
                                    "gauss4:h=0.05",                       # implicit
                                    "rk4:h=0.05+observer:theta=10"])       # modified field
def test_every_kind_of_method_is_located(osc, method):
    r = solve_section(P, method, 2, t_end=15.0)
    c = columns(r)
    assert r.status == "ok" and len(c["t"]) == 2
    assert np.max(np.abs(c["q"])) <= TOL and np.all(c["p"] > 0)
    assert np.max(np.abs(c["t"] - 2 * math.pi * np.arange(1, 3))) <= 1e-3


@pytest.mark.parametrize("method,locator,used", [
    ("rk4:h=0.01", None, "henon"),                                   # fixed step
    ("rkf45:rtol=1e-10,atol=1e-10", None, "henon"),                  # adaptive, no extension
    ("odex:rtol=1e-11,atol=1e-11", None, "henon"),                   # extrapolation
    ("dop853:rtol=1e-12,atol=1e-12", None, "dense"),                 # dense output
    ("dop853:rtol=1e-12,atol=1e-12", "henon", "henon"),              # Hénon asked for
    ("rk4:h=0.01+observer:theta=10", None, "henon"),                 # modified field
])
def test_crossings_against_the_exact_ones(osc, method, locator, used):
    """Located inside the compiled driver, each crossing is the exact one (t = 2 pi k, p = 1) up
    to the global error e_n of the accepted point y_n before it: Hénon's point is on the exact
    flow through y_n (a rotation here, so it keeps that distance: |t - 2 pi k|, |p - 1| <= e_n;
    under the observer the flow of the modified field, which coincides with it on H = H0), the
    dense one within twice the larger error of the step's two ends. The counters are those of the
    step that holds the crossing; nfev adds the locator's evaluations."""
    r = solve_section(P, method, 4, t_end=30.0, locator=locator)
    traj = solve(P, method, t_end=30.0)
    err = global_errors(traj)
    c = columns(r)
    assert r.status == "ok" and r.provenance["locator"] == used and len(r.t) == 4
    assert np.max(np.abs(c["q"])) <= TOL
    loc = r.provenance["henon" if used == "henon" else "dense"]["nfev"]
    for k in range(4):
        n = int(np.searchsorted(traj.t, r.t[k])) - 1               # t_n < t* <= t_n+1
        bound = 2 * max(err[n], err[n + 1]) if used == "dense" else 1.01 * err[n]
        assert abs(r.t[k] - 2 * math.pi * (k + 1)) <= bound + 1e-13
        assert abs(c["p"][k] - 1.0) <= bound + 1e-13
        assert (r.steps[k], r.rejected[k]) == (traj.steps[n + 1], traj.rejected[n + 1])
        assert traj.nfev[n + 1] < r.nfev[k] <= traj.nfev[n + 1] + loc or (used, loc) == ("dense", 0)
    assert r.nfev[-1] == traj.nfev[n + 1] + loc                   # it stops at the 4th crossing
    if "observer" in method:
        assert "modified: observer" in r.provenance["henon"]["field"]


def test_resumable_whatever_the_buffer_and_budget(monkeypatch):
    """The same crossings, bit for bit, with one row per output buffer and one step per call as
    with large buffers and the tuned budget (the drivers' whole state lives in y_io and st)."""
    from gnibench.suite.cell import sections

    for method in ["rk4:h=0.01", "rkf45:rtol=1e-9,atol=1e-9", "dop853:rtol=1e-10,atol=1e-10",
                   "odex:rtol=1e-9,atol=1e-9"]:
        big = solve_section("henon-heiles", method, 6, t_end=200.0)
        with monkeypatch.context() as m:
            m.setattr(sections, "CHUNK", 1)
            tiny = solve_section("henon-heiles", method, 6, t_end=200.0, budget=1)
        assert len(big.t) == 6, method
        for a, b in [(big.t, tiny.t), (big.y, tiny.y), (big.steps, tiny.steps),
                     (big.nfev, tiny.nfev), (big.rejected, tiny.rejected)]:
            assert np.array_equal(a, b), method


def test_progress_counts_crossings(osc):
    """Between calls the progress callback gets max(crossings / K, t / t_end)."""
    seen = []
    r = solve_section(P, "rk4:h=0.001", 3, t_end=1000.0, progress=seen.append, budget=500)
    assert len(r.t) == 3 and len(seen) >= 30 and seen == sorted(seen)
    assert seen[-1] >= 2 / 3 and all(0.0 <= x <= 1.0 for x in seen)   # t / t_end stays < 0.02


def test_external_engine_samples_are_scanned(osc):
    """heyoka (Taylor, tolerance eps) samples every dt_out; its crossings are found by one
    vectorised scan of the samples and located in one compiled call on the base field: they are
    the exact ones, with heyoka's step count at the sample that ends each interval."""
    r = solve_section(P, "heyoka-taylor:dt_out=0.05", 4, t_end=30.0)
    assert r.status == "ok" and r.provenance["locator"] == "henon"
    assert "base field" in r.provenance["henon"]["field"]
    assert np.max(np.abs(r.t - 2 * math.pi * np.arange(1, 5))) <= 1e-13
    assert np.max(np.abs(r.y[:, 1] - 1.0)) <= 1e-13 and np.max(np.abs(r.y[:, 0])) <= TOL
    assert np.all(np.diff(r.steps) > 0) and r.steps[0] > 0


def test_fewer_crossings_than_asked(osc, capsys):
    code = main(["solve", P, "rk4:h=0.01", "--t-end", "10", "--section", "3"])
    out, err = capsys.readouterr()
    assert code == 0
    assert len(pd.read_csv(io.StringIO(out))) == 1
    assert err.startswith("gnibench: ok: only 1 of 3 crossings")


def _cli(argv, capsys):
    code = main(argv)
    out, err = capsys.readouterr()
    assert code == 0, err
    return pd.read_csv(io.StringIO(out))


def test_gavrilov_shilnikov_cli(capsys):
    d = _cli(["solve", "gavrilov-shilnikov", "rk4:h=0.005", "--t-end", "10", "--section", "4"],
             capsys)
    assert list(d.columns) == ["crossing", "t", "q2", "p2", "q1", "p1", "err_H", "err_K"]
    assert len(d) == 4
    assert d.p1.abs().max() <= TOL and (d.p2 > 0).all()
    # on the homoclinic loop the orbit crosses once per turn, 2 pi / omega = 1
    assert np.abs(np.diff(d.t) - 1.0).max() < 1e-3


def test_euler_so4_cli(capsys):
    d = _cli(["solve", "euler-so4", "rk4:h=0.01", "--steps", "20000", "--section", "40"], capsys)
    assert list(d.columns)[:5] == ["crossing", "t", "chart", "x5", "x6"]
    assert {"x1", "x2", "x3", "x4", "err_H1", "err_H2", "err_H3"} <= set(d.columns)
    assert len(d) == 40 and d.chart.between(1, 8).all() and d.chart.dtype.kind == "i"
    assert d.x2.abs().max() <= TOL
    lam = (1, 5, 2, 1, 3, 4)
    x2dot = (lam[0] - lam[2]) * d.x1 * d.x3 + (lam[3] - lam[5]) * d.x4 * d.x6
    assert (x2dot < 0).all()                        # the catalog's direction: x2' < 0


def test_section_on_problem_without_one(capsys):
    code = main(["solve", "harmonic-oscillator", "rk4", "--steps", "10", "--section", "2"])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    assert len(err.splitlines()) == 1 and err.startswith("gnibench: error:")
    assert "no Poincaré section" in err


@pytest.mark.parametrize("extra", [["--section", "0"], ["--section", "2", "--every", "5"],
                                   ["--section", "2", "--reference", "none"]])
def test_bad_section_options(capsys, extra):
    code = main(["solve", "gavrilov-shilnikov", "rk4", "--steps", "10", *extra])
    out, err = capsys.readouterr()
    assert code == 2 and out == "" and len(err.splitlines()) == 1


# -- dense output ---------------------------------------------------------------------------------

@pytest.mark.parametrize("method", ["dop853:rtol=1e-13,atol=1e-13", "dopri5:rtol=1e-12,atol=1e-12"])
def test_dense_locator_finds_the_exact_crossings(osc, method):
    """The continuous extension's crossing is on the section to round-off, and it is the exact
    crossing (2 pi k, p = 1) within twice the global error of the two samples around it.
    Measured: |q| = 0 (dop853, one 2.2e-19); |t - 2 pi k| <= 2.8e-13 (dop853), 2.5e-13 (dopri5);
    |p - 1| <= 3.4e-13 (dop853), 5.8e-12 (dopri5)."""
    r = solve_section(P, method, 3, t_end=20.0)
    c = columns(r)
    assert r.status == "ok" and r.provenance["locator"] == "dense" and "henon" not in r.provenance
    assert 1 <= r.provenance["dense"]["max_iterations"] <= 10
    # the extension is formed from the accepted step's stages (no recomputation): DOP853's 3 extra
    # stages at each of the 6 sign changes up to the 3rd upward crossing (t = pi, 2 pi, ..., 6 pi)
    assert r.provenance["dense"]["nfev"] == (18 if "dop853" in method else 0)
    assert np.max(np.abs(c["q"])) <= TOL and r.provenance["max_abs_g"] <= TOL
    traj = solve(P, method, t_end=20.0)
    for k in range(3):
        n = np.searchsorted(traj.t, c["t"][k]) - 1              # t_n < t* <= t_n+1
        assert traj.y[n, 0] < 0 <= traj.y[n + 1, 0]
        around = max(global_errors(traj)[n], global_errors(traj)[n + 1])
        print(f"{method} k={k + 1}: dt={c['t'][k] - 2 * math.pi * (k + 1):.2e} "
              f"dp={c['p'][k] - 1:.2e} global error around {around:.2e}")
        assert abs(c["t"][k] - 2 * math.pi * (k + 1)) <= 2 * around + 1e-15
        assert abs(c["p"][k] - 1.0) <= 2 * around + 1e-15
        assert abs(c["t"][k] - 2 * math.pi * (k + 1)) <= (5e-13 if "dop853" in method else 1e-11)


def test_dense_and_henon_locators_agree():
    """henon-heiles, dop853 at 1e-12: the dense crossing (on the interpolant of the step) and
    Hénon's (on the exact flow from the sample before it) differ by the step's local error.
    Measured over 10 crossings: 3.2e-12 in t, 1.5e-12 in the state (20 crossings: 4.5e-12, 2.3e-12)."""
    spec = "dop853:rtol=1e-12,atol=1e-12"
    dense = solve_section("henon-heiles", spec, 10, t_end=200.0)
    henon = solve_section("henon-heiles", spec, 10, t_end=200.0, locator="henon")
    assert (dense.provenance["locator"], henon.provenance["locator"]) == ("dense", "henon")
    a, b = columns(dense), columns(henon)
    assert len(a["t"]) == len(b["t"]) == 10
    assert max(dense.provenance["max_abs_g"], henon.provenance["max_abs_g"]) <= TOL
    state = REGISTRY["henon-heiles"].state
    dt = np.max(np.abs(a["t"] - b["t"]))
    dy = max(np.max(np.abs(a[s] - b[s])) for s in state)
    print(f"dense - henon: |dt| <= {dt:.2e}, |dy| <= {dy:.2e}")
    assert dt <= 1e-11 and dy <= 1e-11
    assert dt > 0                      # two different locators, not one run twice


@pytest.mark.parametrize("method,note", [
    ("dop853:adaptive=false,h=0.05", "fixed step"),
    ("dop853:rtol=1e-10,atol=1e-10+projection:on=H", "+projection"),
    ("rk4:h=0.01", "no continuous extension"),
])
def test_henon_where_dense_output_does_not_apply(osc, method, note):
    r = solve_section(P, method, 2, t_end=15.0)
    assert r.provenance["locator"] == "henon" and note in r.provenance["locator_note"]
    assert "dense" not in r.provenance and r.provenance["henon"]["max_substeps"] >= 4
    assert np.max(np.abs(columns(r)["q"])) <= TOL and len(columns(r)["t"]) == 2


def test_dense_locator_refused_where_it_does_not_apply(osc):
    with pytest.raises(UserError, match="dense output does not locate"):
        solve_section(P, "rk4:h=0.01", 1, t_end=7.0, locator="dense")


@pytest.mark.parametrize("problem, method", [("henon-heiles", "rk4:h=0.01"),
                                             ("henon-heiles", "dop853:rtol=1e-10,atol=1e-10"),
                                             ("euler-so4", "lie-poisson:h=0.01")])
def test_no_crossing_at_all_is_an_empty_table(problem, method):
    """A horizon too short for one crossing crashed in the trajectory's counters ("cannot
    reshape array of size 0", issue 43: both Hénon-Heiles section benchmarks died in their
    warm-up); it is an empty table, status ok, and the reason says how many were found."""
    from gnibench.suite.runs.solving import solve_cell_spec, solve_output

    out = solve_output(solve_cell_spec(problem, method, t_end=0.1, section=1))
    assert out.traj.status == "ok" and "only 0 of 1 crossings" in out.traj.reason
    assert len(out.traj.t) == 0 and out.traj.steps.shape == (0,)
    assert all(len(v) == 0 for v in out.columns.values()) and "crossing" in out.columns
