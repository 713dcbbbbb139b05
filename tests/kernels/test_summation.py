"""Round-off control: the method option sum=compensated (methods/summation.py, [HLW] VIII.5).

The increments are formed first and added with the carried rounding error, so the rounding of
each step is ~ε|Δ| (Δ the increment) instead of ~ε|y|. Runs at steps so small that the truncation
error is far below round-off, four starting phases, errors fitted as a power of the step count n
(RMS over the runs, least squares over the second half of the decades). Measured:

* harmonic oscillator, rk4, h = 1e-4, 10^6 steps: energy error plain 1.3e-14 growing like n^0.96,
  compensated 2.8e-17 and not growing (n^-0.06); global error 3.0e-14 against 5.8e-15;
* circular Kepler orbit, rk4, h = 1e-4, 10^6 steps: global error plain 1.8e-11 growing like
  n^1.54 (Brouwer's law: a random walk of the energy makes the phase drift like n^{3/2}),
  compensated 3.4e-14 (n^1.05: what is left is the rounding in forming the increments, ε|Δ| per
  step, partly systematic, a phase drift ~ε t); angular momentum plain 6.2e-14, compensated 4.8e-17;
* Störmer-Verlet and Yoshida's triple jump (h = 1e-3, 2·10^5 steps; both conserve L exactly):
  L error plain 5.6e-14 (n^0.73) and 7.0e-14 (n^0.97), compensated 3.5e-17 (n^-0.20) and 7.3e-17
  (n^0.31).

So compensated summation turns plain summation's error of the invariants, a random walk or a
drift like n of size ε|y|, into one of size ε|Δ| that hardly grows (100-1000x smaller here), and
stops Brouwer's n^{3/2} growth of the global error. The tests assert these behaviours with
margins: orders of magnitude, and growth exponents.
"""
from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest
from gnibench.methods import COMPILED
from gnibench.methods.explicit_rk import RK4, erk
from gnibench.methods.summation import CHOICES
from gnibench.suite.cell import driver
from gnibench.suite.cell.solve import solve
from gnibench.suite.cell.spec import parse_method, parse_problem

PHASES = (0.3, 1.07, 1.84, 2.61)
WITHOUT_SUM = {"lie-poisson", "generating-function4"}   # no increments of the usual form
# the high-accuracy families beyond the seeds sum compensated by default ([HLW] VIII.5); the seeds'
# methods keep plain sums (the claims are about them as published)
COMPENSATED = {"vern6", "vern7", "vern8", "vern9", "feagin10", "suzuki4", "mclachlan4",
               "kahan-li6", "kahan-li8"}


def exponent(steps: np.ndarray, errors: np.ndarray) -> float:
    """Least-squares slope of log RMS error against log n over the second half of the decades."""
    keep = steps >= math.sqrt(steps[1] * steps[-1])
    return float(np.polyfit(np.log(steps[keep]), np.log(errors[keep]), 1)[0])


def _runs(problem, method: str, steps: int, exact, invariant):
    """RMS over the phases of (global error, invariant error) at the samples, and the samples."""
    g, inv = [], []
    for phi in PHASES:
        spec, y0 = problem(phi)
        traj = solve(spec, method, steps=steps, every=steps // 32, reference="none")
        assert traj.status == "ok"
        g.append([float(mpmath.sqrt(sum((mpmath.mpf(float(a)) - b) ** 2 for a, b in
                                        zip(row, exact(phi, int(k))))))
                  for row, k in zip(traj.y, traj.steps)])
        inv.append(np.abs(invariant(traj.y) - invariant(np.array([y0]))))
    rms = [np.sqrt(np.mean(np.square(np.array(x, dtype=float)), axis=0)) for x in (g, inv)]
    return np.asarray(traj.steps), rms[0], rms[1]


def _oscillator(h):
    def problem(phi):
        q0, p0 = math.cos(phi), math.sin(phi)
        return f"harmonic-oscillator:q0={q0!r},p0={p0!r}", (q0, p0)

    def exact(phi, k):
        mpmath.mp.dps = 30
        t = k * mpmath.mpf(h)
        q0, p0 = mpmath.mpf(math.cos(phi)), mpmath.mpf(math.sin(phi))
        return (q0 * mpmath.cos(t) + p0 * mpmath.sin(t), -q0 * mpmath.sin(t) + p0 * mpmath.cos(t))

    def energy(y):
        y = y.astype(np.longdouble)
        return 0.5 * (y[:, 0] ** 2 + y[:, 1] ** 2)

    return problem, exact, energy


def _circular_kepler(h):
    def problem(phi):
        c, s = math.cos(phi), math.sin(phi)
        return f"kepler-2d:e=0,p10={-s!r},p20={c!r},q10={c!r},q20={s!r}", (-s, c, c, s)

    def exact(phi, k):
        mpmath.mp.dps = 30
        t = k * mpmath.mpf(h) + mpmath.mpf(phi)
        return (-mpmath.sin(t), mpmath.cos(t), mpmath.cos(t), mpmath.sin(t))

    def momentum(y):
        y = y.astype(np.longdouble)
        return y[:, 2] * y[:, 1] - y[:, 3] * y[:, 0]

    return problem, exact, momentum


def test_every_compiled_one_step_method_has_the_option():
    for mid, m in COMPILED.items():
        names = [p.name for p in m.params]
        if mid in WITHOUT_SUM:
            assert "sum" not in names
            continue
        param = next(p for p in m.params if p.name == "sum")
        wanted = "compensated" if mid in COMPENSATED else "plain"
        assert param.default == m.summation == wanted and param.choices == CHOICES, mid


def test_the_default_is_a_field_of_the_method_record():
    accurate = erk("rk4-compensated", RK4, "test", "rk4 summing compensated by default",
                   summation="compensated")
    problem = parse_problem("kepler-2d")
    assert next(p for p in accurate.params if p.name == "sum").default == "compensated"
    cfg = parse_method("rk4:sum=compensated", problem)
    assert cfg.base.values["sum"] == "compensated" and cfg.text() == "rk4:h=0.01,sum=compensated"
    assert parse_method("rk4:sum=plain", problem).text() == "rk4:h=0.01"   # plain: as before


@pytest.mark.parametrize("method,kw", [
    ("rk4:h=0.05", {"steps": 400, "dt_out": 0.7}),
    ("yoshida4:h=0.05", {"steps": 400, "every": 7}),
    ("gauss4:h=0.05", {"steps": 300, "every": 9}),
    ("dop853:rtol=1e-10,atol=1e-10", {"t_end": 25.0, "dt_out": 0.7}),
    ("odex:rtol=1e-10,atol=1e-10", {"t_end": 25.0, "dt_out": 0.7}),
    ("rkf45:rtol=1e-8,atol=1e-8", {"t_end": 25.0, "every": 5}),
])
def test_the_carry_persists_across_calls(monkeypatch, method, kw):
    """The result does not depend on where the runs pause or how small the output buffer is."""
    spec = method + ",sum=compensated"
    whole = solve("kepler-2d", spec, budget=None, **kw)
    monkeypatch.setattr(driver, "ADAPTIVE_CHUNK", 3)
    monkeypatch.setattr(driver, "GRID_ROWS", 3)
    pieces = solve("kepler-2d", spec, budget=2, **kw)
    for a, b in ((whole.t, pieces.t), (whole.y, pieces.y), (whole.nfev, pieces.nfev)):
        assert np.array_equal(a, b)


def test_sections_with_the_carry_are_resumable(monkeypatch):
    spec = "dopri5:rtol=1e-10,atol=1e-10,sum=compensated"
    whole = solve("henon-heiles", spec, t_end=200.0, section=25, budget=None)
    pieces = solve("henon-heiles", spec, t_end=200.0, section=25, budget=3)
    assert len(whole.t) == 25 and np.array_equal(whole.y, pieces.y)


def test_round_off_on_the_harmonic_oscillator():
    h, n = 1e-4, 10**6
    problem, exact, energy = _oscillator(h)
    steps, g_plain, e_plain = _runs(problem, f"rk4:h={h!r}", n, exact, energy)
    _, g_comp, e_comp = _runs(problem, f"rk4:h={h!r},sum=compensated", n, exact, energy)
    assert e_comp[-1] < e_plain[-1] / 30                  # measured: 2.8e-17 vs 1.3e-14
    assert exponent(steps, e_plain) > 0.5                 # plain: like n (0.96)
    assert exponent(steps, e_comp) < 0.5                  # compensated: no growth (-0.06)
    assert g_comp[-1] < g_plain[-1]                       # 5.8e-15 vs 3.0e-14


def test_round_off_on_the_kepler_problem():
    h, n = 1e-4, 10**6
    problem, exact, momentum = _circular_kepler(h)
    steps, g_plain, l_plain = _runs(problem, f"rk4:h={h!r}", n, exact, momentum)
    _, g_comp, l_comp = _runs(problem, f"rk4:h={h!r},sum=compensated", n, exact, momentum)
    assert g_comp[-1] < g_plain[-1] / 100                 # measured: 3.4e-14 vs 1.8e-11
    assert exponent(steps, g_plain) > 1.3                 # Brouwer: n^{3/2} (1.54)
    assert exponent(steps, g_comp) < 1.25                 # ε|Δ| per step, a phase drift (1.05)
    assert l_comp[-1] < l_plain[-1] / 30                  # 4.8e-17 vs 6.2e-14
    assert exponent(steps, l_comp) < 0.5                  # -0.05


@pytest.mark.parametrize("method", ["stormer-verlet", "yoshida4"])
def test_round_off_of_a_partitioned_method_and_a_composition(method):
    """Each block update of each stage adds its increment with the carry: the angular momentum,
    which these methods conserve exactly, keeps only the rounding of the increments."""
    h, n = 1e-3, 2 * 10**5
    problem, exact, momentum = _circular_kepler(h)
    steps, _, l_plain = _runs(problem, f"{method}:h={h!r}", n, exact, momentum)
    _, _, l_comp = _runs(problem, f"{method}:h={h!r},sum=compensated", n, exact, momentum)
    assert l_comp[-1] < l_plain[-1] / 30                  # measured: ratios 1600 and 960
    assert exponent(steps, l_comp) < 0.6                  # -0.20 and 0.31


def test_tolerances_below_the_unit_round_off_on_kepler():
    """End to end on wp-kepler-2d's cell (e = 0.6, 20 periods, against Kepler's equation in long
    double): Feagin's 10(8) at rtol = 1e-17, below the unit round-off. The truncation error is
    then far below 1e-13 and what is left is round-off: plain sums of y and t stop near 3e-12,
    compensated ones (the y and t carries, the last step landing on t_end) go below 1e-12.
    Measured: plain 2.9e-12, compensated 1.3e-13 (3377 steps, t_final == t_end both)."""
    t_end = 40 * math.pi
    final = {}
    for how in CHOICES:
        traj = solve("kepler-2d", f"feagin10:rtol=1e-17,atol=1e-18,sum={how}", t_end=t_end,
                     every=10**6)
        assert traj.status == "ok" and traj.t[-1] == t_end
        final[how] = float(np.sqrt(np.sum((traj.y[-1] - traj.reference.y[-1]) ** 2)))
    assert final["compensated"] < 1e-12
    assert final["compensated"] < final["plain"] / 4
