"""Divergent integrations are results, not crashes.

A state that overflows ends the run with status ``nonfinite``; a Newton iteration that does not
converge ends it with ``newton_failed``. Either way every sample taken so far is kept, plus the last
good point, and the CLI still exits 0, writes the table and reports the status on stderr. The kept
samples are checked against an independent numpy/scipy iteration of the same one-step maps:
explicit Euler [HLW] (1.5) and the implicit midpoint rule [HLW] (1.7) on Kepler [HLW] (2.2).
"""
from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import pytest
from gnibench.suite.cell.solve import solve
from gnibench.suite.cli.main import main
from gnibench.suite.metrics.invariants import invariant_errors
from scipy.optimize import fsolve

H_HUGE = 1e153                  # q1 drifts by -6.25 h² per step: overflow after ~30 steps


def kepler_field(y):
    """[HLW] (2.2)-(2.3) in the state order (p1, p2, q1, q2)."""
    p1, p2, q1, q2 = y
    r3 = (q1 * q1 + q2 * q2) ** 1.5
    return np.array([-q1 / r3, -q2 / r3, p1, p2])


def euler_until_overflow(y0, h, nmax):
    """Independent Euler iterates up to (excluding) the first non-finite one."""
    ys = [np.array(y0, dtype=float)]
    with np.errstate(all="ignore"):
        for _ in range(nmax):
            y1 = ys[-1] + h * kepler_field(ys[-1])
            if not np.all(np.isfinite(y1)):
                break
            ys.append(y1)
    return np.array(ys)


@pytest.mark.parametrize("every", [1, 3, 100])
def test_euler_overflow_is_nonfinite_with_samples_kept(every):
    """Euler with h = 1e153 on kepler-2d overflows after ~30 steps: status nonfinite."""
    ref = euler_until_overflow((0.0, 2.0, 0.4, 0.0), H_HUGE, 1000)
    good = len(ref) - 1                                # steps done before the overflow
    assert 1 < good < 1000
    with np.errstate(all="ignore"):
        r = solve("kepler-2d", f"euler:h={H_HUGE}", steps=1000, every=every)
    assert r.status == "nonfinite"
    assert f"step {good + 1}" in r.reason
    want_steps = sorted(set(range(0, good + 1, every)) | {good})
    assert r.steps.tolist() == want_steps
    assert np.all(np.isfinite(r.y))
    np.testing.assert_allclose(r.y, ref[want_steps], rtol=1e-15, atol=0)
    np.testing.assert_allclose(r.t, np.array(want_steps) * H_HUGE, rtol=1e-15)
    assert invariant_errors(r).shape == (len(want_steps), len(r.integral_names))


def implicit_midpoint_step(y, h, field):
    """[HLW] (1.7) solved by scipy: y1 = y + h f((y + y1)/2) (residual checked, not fsolve's flag)."""
    def residual(z):
        return z - y - h * field((y + z) / 2)

    z = fsolve(residual, y + h * field(y), xtol=1e-14, full_output=True)[0]
    assert np.max(np.abs(residual(z))) <= 1e-13 * max(1.0, np.max(np.abs(z)))
    return z


def test_newton_failure_mid_run_keeps_good_steps():
    """Implicit midpoint, h = 0.3, from the apocentre of the e = 0.6 orbit: near the pericentre
    (1.7) has no solution Newton can reach (scipy's fsolve fails there too); the steps before are
    kept and agree with fsolve's solution of (1.7)."""
    va = math.sqrt(0.4 / 1.6)
    spec = f"kepler-2d:p10=0,p20={-va!r},q10=-1.6,q20=0"
    r = solve(spec, "implicit-midpoint:h=0.3", steps=200, every=1)
    assert r.status == "newton_failed"
    done = int(r.steps[-1])
    assert 3 <= done < 30 and f"step {done + 1}" in r.reason
    assert r.steps.tolist() == list(range(done + 1))
    np.testing.assert_allclose(r.t, 0.3 * np.arange(done + 1), rtol=1e-15)
    for k in range(done):
        y1 = implicit_midpoint_step(r.y[k], 0.3, kepler_field)
        np.testing.assert_allclose(r.y[k + 1], y1, rtol=0, atol=1e-13)


@pytest.mark.parametrize("pid,method", [("lotka-volterra", "implicit-euler:h=0.1,newton_maxit=1"),
                                        ("kepler-2d", "implicit-midpoint:h=1.5")])
def test_newton_failure_at_first_step(pid, method):
    """No converged step at all: the table is the initial point alone, with the status set."""
    r = solve(pid, method, steps=10)
    assert r.status == "newton_failed" and "step 1" in r.reason
    assert r.steps.tolist() == [0] and r.t.tolist() == [0.0]
    assert np.array_equal(r.y[0], np.array(r.y0))
    assert np.all(invariant_errors(r) == 0)


@pytest.mark.parametrize("fmt", ["csv", "json", "parquet"])
def test_cli_writes_the_table_and_reports_status(fmt, tmp_path, capsys):
    """The CLI exits 0, writes every kept row, and puts the status on stderr (one line)."""
    out_path = tmp_path / f"div.{fmt}"
    with np.errstate(all="ignore"):
        code = main(["solve", "kepler-2d", f"euler:h={H_HUGE}", "--steps", "1000", "--every", "3",
                     "--format", fmt, "-o", str(out_path)])
    out, err = capsys.readouterr()
    assert code == 0 and out == ""
    assert err.startswith("gnibench: nonfinite:") and len(err.splitlines()) == 1
    assert "Traceback" not in err
    good = len(euler_until_overflow((0.0, 2.0, 0.4, 0.0), H_HUGE, 1000)) - 1
    want_steps = sorted(set(range(0, good + 1, 3)) | {good})
    if fmt == "csv":
        df = pd.read_csv(out_path)
    elif fmt == "parquet":
        df = pd.read_parquet(out_path)
    else:
        doc = json.loads(out_path.read_text())
        assert doc["meta"]["status"] == "nonfinite" and doc["meta"]["reason"]
        df = pd.DataFrame(doc["columns"])
    assert df["steps"].tolist() == want_steps
    assert np.all(np.isfinite(df[["p1", "p2", "q1", "q2"]].to_numpy()))


def test_a_run_that_fills_its_output_budget_ends_max_rows_with_its_samples(monkeypatch):
    """A growing output buffer (adaptive steps, a section, a transformed time's grid) stops at the
    output budget with status ``max_rows``, keeping the rows written: the unplanned rows of a K-S
    run whose physical time ran away (mutant symplectic-euler-stale-force) grew until the OOM
    killer ended the pool worker (23 GB). The samples kept are the unbounded run's own."""
    monkeypatch.setenv("GNIBENCH_MAX_ROWS", "100")
    capped = solve("kepler-2d", "dopri5:rtol=1e-10,atol=1e-10", t_end=628.0)
    assert str(capped.status) == "max_rows" and len(capped.t) == 100
    monkeypatch.delenv("GNIBENCH_MAX_ROWS")
    whole = solve("kepler-2d", "dopri5:rtol=1e-10,atol=1e-10", t_end=10.0)
    assert np.array_equal(whole.t[:99], capped.t[:99]) and np.array_equal(whole.y[:99], capped.y[:99])
    assert "GNIBENCH_MAX_ROWS=100" in capped.reason and "after 100 rows" in capped.reason


@pytest.mark.parametrize("fmt", ["csv", "json"])
def test_solve_stopped_by_the_output_budget_says_so_and_exits_1(monkeypatch, capsys, fmt):
    """The rows so far are written, one line on stderr names the budget, and the exit code is not
    0: the output is not what was asked for (before: exit 0, an empty reason, no line in csv)."""
    monkeypatch.setenv("GNIBENCH_MAX_ROWS", "50")
    code = main(["solve", "kepler-2d", "dopri5", "--t-end", "100", "--format", fmt])
    out, err = capsys.readouterr()
    assert code == 1
    assert err.startswith("gnibench: max_rows: the output budget is full at t = ")
    assert "GNIBENCH_MAX_ROWS=50" in err and len(err.splitlines()) == 1
    if fmt == "csv":
        assert len(out.splitlines()) == 51
    else:
        assert json.loads(out)["meta"]["status"] == "max_rows"


def test_ias15_failing_at_its_first_sample_keeps_no_sample(monkeypatch):
    """rebound's errors end an IAS15 run as a status (``nonfinite``, rebound's error in the
    reason): the samples kept are the samples reached, here none, as the engine's run (rows of y,
    steps and nfev) and as the trajectory. The failure is rebound raising at its first
    ``Simulation.integrate`` call (a collision, as with collision detection on)."""
    import rebound
    from gnibench.methods.engines.rebound import rebound_propagate
    from gnibench.suite.cell.spec import parse_problem

    def collide(self, *args, **kwargs):
        raise rebound.Collision("two particles collided")

    monkeypatch.setattr(rebound.Simulation, "integrate", collide)
    run = rebound_propagate(parse_problem("kepler-2d"), np.array([0.0, 0.5, 1.0]), "ias15")
    assert (run.status, run.reason) == ("nonfinite",
                                        "rebound stopped: Collision: two particles collided")
    assert run.y.shape == (0, 4) and len(run.steps) == 0 and len(run.nfev) == 0
    r = solve("kepler-2d", "rebound-ias15:dt_out=0.5", t_end=2.0)
    assert r.status == "nonfinite" and r.reason == run.reason
    assert len(r.t) == 0 and r.y.shape == (0, 4) and len(r.steps) == len(r.nfev) == 0
