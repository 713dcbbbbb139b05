"""The time variable under ``sum=compensated`` is the exact sum of the accepted steps, rounded.

methods/summation.py: "The time t of the adaptive drivers is summed the same way (slot
ST_T_CARRY), and their last step is (t_end - t_n) - e_t, so the steps add up to t_end"; the
fixed-step driver's time is the product n h (the last step h_last), not a running sum. So in every
driver the time of the n-th accepted point is, to 1 ulp, ``math.fsum`` of the sizes of the
accepted steps before it ([HLW] VIII.5), and the last one is t_end exactly:

* the adaptive driver (embedded pairs, ODEX), from its per-step samples with the size of each step
  (the 5th counter column of integrate_adaptive); under ``sum=plain`` the time is instead the
  running float sum, which on these runs is more than 1 ulp away from fsum (so the check can fail);
* its time-grid variants (dense output, partial steps) take exactly the same steps: same final
  point and step count, bit for bit, as the per-step driver;
* the fixed-step driver, from its samples: t_n = n h to 1 ulp of fsum([h] * n).
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from gnibench.suite.cell.calls import Buffers
from gnibench.suite.cell.drivers import AdaptiveDriver
from gnibench.suite.cell.solve import solve
from gnibench.suite.cell.spec import prepare

T_END = 12 * math.pi


def per_step(method: str, driver: str = "integrate_adaptive", **kw):
    prob, cfg = prepare("kepler-2d:e=0.6", method)
    drv = AdaptiveDriver(prob, cfg, driver, T_END, **kw)
    buffers = Buffers(1 << 15, 4, grow=False)
    code, _ = drv.run(buffers, budget=None)
    assert code == "ok"
    t, y, c = buffers.arrays()
    return t, y, c


def ulps_from_fsum(t: np.ndarray, h: np.ndarray) -> np.ndarray:
    """|t_n - fsum(h_1..h_n)| in ulps of t_n, for every n >= 1."""
    sums = np.array([math.fsum(h[1:n + 1]) for n in range(1, len(t))])
    return np.abs(t[1:] - sums) / np.spacing(np.abs(t[1:]))


@pytest.mark.parametrize("method", ["dopri5:rtol=1e-12,atol=1e-12", "odex:rtol=1e-12,atol=1e-12"])
def test_adaptive_time_is_the_compensated_sum_of_the_steps(method):
    t, _, c = per_step(f"{method},sum=compensated")
    h = c[:, 4]
    assert len(t) > 80 and h[0] == 0.0 and np.all(h[1:] > 0)
    assert t[-1] == T_END
    assert np.max(ulps_from_fsum(t, h)) <= 1.0
    # sum=plain: the running float sum, which drifts from the exact sum of the same steps
    tp, _, cp = per_step(f"{method},sum=plain")
    hp = cp[:, 4]
    running = np.zeros(len(tp))
    for n in range(1, len(tp) - 1):
        running[n] = running[n - 1] + hp[n]
    assert np.array_equal(tp[1:-1], running[1:-1]) and tp[-1] == T_END
    assert np.max(ulps_from_fsum(tp[:-1], hp[:-1])) > 1.0       # the check tells them apart


@pytest.mark.parametrize("method", ["dopri5", "dopri5+projection:on=H", "odex"])
def test_time_grid_drivers_take_the_same_compensated_steps(method):
    """dopri5: dense output (integrate_dense); with a step modifier, and odex: partial steps
    (adaptive_grid)."""
    base, _, mod = method.partition("+")
    spec = f"{base}:rtol=1e-12,atol=1e-12,sum=compensated" + (f"+{mod}" if mod else "")
    steps = solve("kepler-2d:e=0.6", spec, t_end=T_END)
    grid = solve("kepler-2d:e=0.6", spec, t_end=T_END, dt_out=T_END / 7)
    assert grid.provenance["time_grid"]["locator"] == ("partial step" if mod or base == "odex"
                                                       else "dense output")
    assert np.array_equal(grid.t[:-1], np.arange(7) * (T_END / 7)) and grid.t[-1] == T_END
    assert np.array_equal(grid.y[-1], steps.y[-1]) and grid.steps[-1] == steps.steps[-1]


@pytest.mark.parametrize("method", ["rk4:h=0.01", "stormer-verlet:h=0.01"])
def test_fixed_step_time_is_the_product(method):
    traj = solve("kepler-2d:e=0.6", f"{method},sum=compensated", t_end=7.005, every=1)
    t = traj.t
    h = 0.01
    n = np.arange(len(t))
    sums = np.array([math.fsum([h] * k) for k in n[:-1]])
    assert np.max(np.abs(t[:-1] - sums) / np.spacing(np.maximum(np.abs(t[:-1]), h))) <= 1.0
    assert t[-1] == 7.005
