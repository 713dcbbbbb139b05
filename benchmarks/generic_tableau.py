"""Explicit Runge-Kutta steps both ways (issue 19: coefficients as run-time data or as constants).

Both compute the explicit Runge-Kutta step of [HLW] II.1.1 (Def. 1.1), k_i = f(y + h Σ_j a_ij k_j),
y1 = y + h Σ_i b_i k_i (Euler, [HLW] (1.5), is its one-stage case): the written-out step of
gnibench's kernels (``methods/explicit_rk.py``: stages unrolled, the tableau's doubles as literals,
zero entries left out) against one generic step that reads the tableau at run time (the non-zero
entries of each row of A and of b in arrays), which a single compiled kernel per problem could share
across every explicit method. Both call the same field ``f`` of the same cell module, on kepler-2d
(e = 0.6), in the same bare loop of 200 000 steps; printed: ns per step (best of 15) and the final
states' largest difference.

Run: ``python benchmarks/generic_tableau.py`` (a measurement, not a test).
"""
from __future__ import annotations

import sys
import time

import numpy as np
from gnibench.methods.embedded_rk import DOP853
from gnibench.methods.explicit_rk import RK4
from gnibench.suite.api.solving import solve
from numba import njit

STEPS = 200_000
H = 0.01
Y0 = (0.0, 2.0, 0.4, 0.0)              # kepler-2d's (p1, p2, q1, q2) with e = 0.6
PAR = np.array([1.0])                  # kepler-2d's field reads no parameter


def cell_module(spec: str):
    """The compiled module of the kepler-2d cell of ``spec`` (compiled or loaded by a solve)."""
    before = set(sys.modules)
    solve("kepler-2d", spec, t_end=0.1)
    (name,) = [m for m in set(sys.modules) - before if "cell_" in m]
    return sys.modules[name]


def sparse(tab):
    """The kernels' doubles of ``tab`` as arrays: A's non-zero entries row by row (values,
    columns, row starts) and b's non-zero entries (values, columns)."""
    a, b = tab.doubles
    val, col, ptr = [], [], [0]
    for i in range(len(b)):
        for j in range(i):
            if a[i][j] != 0.0:
                val.append(a[i][j])
                col.append(j)
        ptr.append(len(val))
    bcol = [j for j in range(len(b)) if b[j] != 0.0]
    return (np.array(val), np.array(col, np.int64), np.array(ptr, np.int64),
            np.array([b[j] for j in bcol]), np.array(bcol, np.int64))


def generic_loop(f):
    @njit
    def step(y, h, par, val, col, ptr, bval, bcol, k):
        for i in range(ptr.shape[0] - 1):
            a0 = a1 = a2 = a3 = 0.0
            for p in range(ptr[i], ptr[i + 1]):
                w, j = val[p], col[p]
                a0 += w * k[j, 0]
                a1 += w * k[j, 1]
                a2 += w * k[j, 2]
                a3 += w * k[j, 3]
            z = f((y[0] + h * a0, y[1] + h * a1, y[2] + h * a2, y[3] + h * a3), par)
            k[i, 0], k[i, 1], k[i, 2], k[i, 3] = z
        a0 = a1 = a2 = a3 = 0.0
        for p in range(bval.shape[0]):
            w, j = bval[p], bcol[p]
            a0 += w * k[j, 0]
            a1 += w * k[j, 1]
            a2 += w * k[j, 2]
            a3 += w * k[j, 3]
        return (y[0] + h * a0, y[1] + h * a1, y[2] + h * a2, y[3] + h * a3)

    @njit
    def loop(y, h, par, n, val, col, ptr, bval, bcol, k):
        for _ in range(n):
            y = step(y, h, par, val, col, ptr, bval, bcol, k)
        return y

    return loop


def written_loop(step):
    @njit
    def loop(y, h, par, n, ws):
        for _ in range(n):
            y, _nf, _nj, _s = step(y, h, par, ws)
        return y

    return loop


def best(run) -> tuple[float, tuple]:
    times = []
    for _ in range(15):
        start = time.perf_counter()
        y = run()
        times.append(time.perf_counter() - start)
    return min(times) / STEPS * 1e9, y


def main() -> None:
    for name, spec, tab in (("rk4", "rk4:h=0.01", RK4),
                            ("dop853", "dop853:adaptive=false,h=0.01", DOP853.tab)):
        mod = cell_module(spec)
        data = sparse(tab)
        k = np.zeros((len(tab.b), 4))
        generic, written = generic_loop(mod.f), written_loop(mod.step)
        ns_g, y_g = best(lambda: generic(Y0, H, PAR, STEPS, *data, k))  # noqa: B023
        ns_w, y_w = best(lambda: written(Y0, H, PAR, STEPS, 0))         # noqa: B023
        diff = max(abs(u - v) for u, v in zip(y_g, y_w))
        print(f"{name:7s} written {ns_w:6.1f} ns/step   generic {ns_g:6.1f} ns/step   "
              f"ratio {ns_g / ns_w:.2f}   final states differ by {diff:.1e}")


if __name__ == "__main__":
    main()
