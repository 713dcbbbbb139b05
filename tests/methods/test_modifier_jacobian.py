"""The Jacobian of a modified field ([B] (2.5) observer, (2.10) penalty), which Newton of the
implicit methods uses, against central differences of the compiled field itself: a wrong sign or a
missing term of the modifier's Jacobian still lets Newton converge (slower) to the same point, so
no integration result sees it; this test does. The modifier's Jacobian is its leading term
-D_Hᵀ W D_H (methods/modifiers.py); the terms it omits carry the factor H0 - H, so the comparison
is made on the invariant manifold: at points of an accurate solution (dop853, tol 1e-12)."""
from __future__ import annotations

import numpy as np
import pytest
from gnibench.suite.cell.compiled import compile_cell
from gnibench.suite.cell.solve import solve
from gnibench.suite.cell.spec import prepare

CASES = [("kepler-2d:e=0.6", "implicit-midpoint:h=0.01+observer:on=H/L"),
         ("kepler-2d:e=0.6", "implicit-midpoint:h=0.01+observer:mode=simple,on=H/L,theta=2/3"),
         ("kepler-2d:e=0.6", "implicit-midpoint:h=0.01+penalty:on=H/L"),
         ("henon-heiles", "gauss4:h=0.01+observer:on=H")]


@pytest.mark.parametrize("problem, method", CASES)
def test_modified_jacobian_is_the_derivative_of_the_modified_field(problem, method):
    prob, cfg = prepare(problem, method)
    cell = compile_cell(prob, cfg)
    f, fjac, par = cell.kernel.f, cell.kernel.fjac, cell.par
    n = len(cell.y0)
    orbit = solve(problem, "dop853:rtol=1e-12,atol=1e-12", t_end=3.0, dt_out=0.6)
    assert orbit.status == "ok" and len(orbit.t) == 6
    for y in orbit.y[1:]:
        J = np.zeros((n, n))
        fjac(tuple(y), par, J)
        D = np.empty((n, n))
        for j in range(n):
            step = 1e-6 * max(1.0, abs(y[j]))
            up, down = y.copy(), y.copy()
            up[j] += step
            down[j] -= step
            D[:, j] = (np.array(f(tuple(up), par)) - np.array(f(tuple(down), par))) / (2 * step)
        scale = max(1.0, float(np.abs(D).max()))
        assert np.abs(J - D).max() < 1e-6 * scale, (problem, method, np.abs(J - D).max(), scale)
