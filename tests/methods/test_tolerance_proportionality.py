"""Adaptive embedded pairs: the global error is proportional to a power of the tolerance.

Kepler (e = 0.6, [HLW] (2.11)) over two periods, exact reference from Kepler's equation, rtol = atol
from 1e-5 to 1e-11. With steps chosen so that the estimated local error is ~tol:
- local extrapolation (the propagated solution has the higher order p, DOPRI5, DOP853): local
  error ~ tol^((p+1)/p) per step over ~tol^(-1/p) steps, so the global error ~ tol (HNW I §II.4);
- no local extrapolation (RKF45, Merson propagate order 4 and estimate with order 5): local error
  ~ tol per step over ~tol^(-1/5) steps, so the global error ~ tol^(4/5);
and the number of f-evaluations grows like tol^(-1/(q+1)), q the order the estimate controls
(4 for the 5(4) and 4(5) pairs, 7 for DOP853's 8(5,3) combination). Least-squares slopes over the
seven tolerances must lie within 0.25 (error) and 0.06 (cost) of these values.
Measured: error slopes dopri5 1.00, dop853 1.13, rkf45 0.90, merson 0.81; cost slopes 0.17, 0.10,
0.18, 0.23.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from gnibench.suite.cell.solve import solve
from gnibench.suite.metrics.global_error import global_errors

TOLS = [1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11]
CASES = {  # method spec prefix: (expected error slope, expected cost slope)
    "dopri5:": (1.0, 1 / 5),
    "dop853:": (1.0, 1 / 8),
    "rkf45:": (0.8, 1 / 5),
    "merson:adaptive=true,": (0.8, 1 / 5),
}


@pytest.mark.parametrize("prefix", list(CASES))
def test_global_error_follows_the_tolerance(prefix):
    err_slope, cost_slope = CASES[prefix]
    errs, costs = [], []
    for tol in TOLS:
        r = solve("kepler-2d", f"{prefix}rtol={tol!r},atol={tol!r}", t_end=4 * math.pi,
                  every=10**6)
        assert r.status == "ok"
        errs.append(global_errors(r)[-1])
        costs.append(r.nfev[-1])
    x = np.log(TOLS)
    slope = np.polyfit(x, np.log(errs), 1)[0]
    cost = -np.polyfit(x, np.log(costs), 1)[0]
    assert abs(slope - err_slope) <= 0.25, (prefix, slope, errs)
    assert abs(cost - cost_slope) <= 0.06, (prefix, cost, costs)
    assert all(np.diff(costs) > 0), costs                # tighter tolerance, more work
