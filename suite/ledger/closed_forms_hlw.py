"""Measurements of [HLW] Ch. I's qualitative claims on the runs' samples: quantities that no
per-cell metric computes (returns of a periodic orbit, the order of maxima in a cycle, the
left-right asymmetry of an orbit, the geometry of the outer solar system).

Each function takes the selected cells (rows of ``cells.parquet``) and the samples table and returns
named values for the claim's ``measured`` and ``passes`` expressions (registered in
:mod:`gnibench.suite.ledger.closed_forms`).
"""
from __future__ import annotations

import math

import numpy as np


def _rows(samples, cell):
    return samples[samples["cell"] == cell]


def _lv_field(u, v):
    """[HLW] (1.1): u' = u(v − 2), v' = v(1 − u)."""
    return u * (v - 2.0), v * (1.0 - u)


def _hermite(t0, t1, y0, y1, f0, f1, s):
    """Cubic Hermite interpolant on [t0, t1] at the fraction s (error O(Δt⁴))."""
    d = t1 - t0
    h00, h10 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s
    h01, h11 = -2 * s**3 + 3 * s**2, s**3 - s**2
    return h00 * y0 + h10 * d * f0 + h01 * y1 + h11 * d * f1


def _lv_returns(rows) -> tuple[list[float], list[float]]:
    """Returns of an LV orbit to the line v = v0 in the direction of its start: the times and
    the distances |u − u0| there (located by cubic Hermite interpolation with the exact field)."""
    t, u, v = (rows[k].to_numpy(dtype=float) for k in ("t", "u", "v"))
    fu, fv = _lv_field(u, v)
    g = v - v[0]
    sign = math.copysign(1.0, fv[0]) if fv[0] != 0 else 1.0
    times, dist = [], []
    crossed = (sign * g[1:-1] < 0) & (sign * g[2:] >= 0) & (sign * fv[2:] > 0)
    for i in np.flatnonzero(crossed) + 1:          # a few returns: locate each one
        lo, hi = 0.0, 1.0                       # bisection on the Hermite interpolant of v
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            gm = _hermite(t[i], t[i + 1], g[i], g[i + 1], fv[i], fv[i + 1], mid)
            lo, hi = (mid, hi) if sign * gm < 0 else (lo, mid)
        s = 0.5 * (lo + hi)
        times.append(t[i] + s * (t[i + 1] - t[i]))
        dist.append(abs(_hermite(t[i], t[i + 1], u[i], u[i + 1], fu[i], fu[i + 1], s) - u[0]))
    return times, dist


def lv_periodic(cells, samples) -> dict:
    """[HLW] after (1.4), HLW-1.1-b: every solution returns to its start. For each cell (an
    accurate run), the returns to the line v = v0 crossed as at t = 0; ``distance`` is the largest
    |u − u0| there, ``period_spread`` the largest |T_k − k T_1| / T_1 over the returns."""
    worst, spread, returns = 0.0, 0.0, math.inf
    for cell in cells["cell"]:
        times, dist = _lv_returns(_rows(samples, cell))
        returns = min(returns, len(times))
        if times:
            worst = max(worst, max(dist))
            spread = max(spread, max(abs(tk - (k + 1) * times[0]) / times[0]
                                     for k, tk in enumerate(times)))
    return {"distance": worst if returns else math.inf, "period_spread": spread,
            "returns": float(returns), "measured": worst if returns else math.inf}


def _maxima(t, x):
    i = np.nonzero((x[1:-1] > x[:-2]) & (x[1:-1] >= x[2:]))[0] + 1
    return t[i]


def lv_stages(cells, samples) -> dict:
    """[HLW] text after Fig 1.1, HLW-1.1-c: in each cycle the prey v peaks before the predator u.
    ``fraction`` = share of the maxima of u (between two maxima of v) that lie nearer to the
    preceding maximum of v than to the following one, i.e. in the first half of v's cycle."""
    good, total = 0, 0
    for cell in cells["cell"]:
        rows = _rows(samples, cell)
        t = rows["t"].to_numpy(dtype=float)
        v_max = _maxima(t, rows["v"].to_numpy(dtype=float))
        for s in _maxima(t, rows["u"].to_numpy(dtype=float)):
            k = np.searchsorted(v_max, s)
            if 0 < k < len(v_max):
                total += 1
                good += s - v_max[k - 1] < v_max[k] - s
    return {"fraction": good / total if total else math.nan, "cycles": float(total),
            "measured": good / total if total else math.nan}


def _asymmetry(q, p) -> float:
    """Largest distance from the mirror image (−q, p) of an orbit point to the nearest orbit point,
    q on the circle [−π, π) (the pendulum's phase space is a cylinder, [HLW] I.1.3).

    Exact, and fast on the dense curves a long run traces (10⁵ points on one closed orbit): the
    tree is built by sliding midpoints without shrinking the boxes to the data (on points along a
    curve the queries of a balanced, compact tree visit several times more leaves), and the
    nearest distances of every 64th mirror point give a lower bound of the largest; the other
    points are searched only within it (``distance_upper_bound``), those found farther again
    without a bound. Same value as querying every point without a bound."""
    from scipy.spatial import cKDTree

    q = np.mod(q + np.pi, 2 * np.pi) - np.pi
    pts = np.column_stack([q, p])
    tree = cKDTree(np.vstack([pts, pts + [2 * np.pi, 0], pts - [2 * np.pi, 0]]),
                   balanced_tree=False, compact_nodes=False)
    mirror = np.column_stack([-q, p])
    worst = float(np.max(tree.query(mirror[::64])[0]))
    dist, _ = tree.query(mirror, distance_upper_bound=worst)
    farther = ~(dist <= worst)                   # inf: no orbit point within the bound
    if farther.any():
        worst = max(worst, float(np.max(tree.query(mirror[farther])[0])))
    return worst


def pendulum_asymmetry(cells, samples) -> dict:
    """[HLW] Fig 1.4, HLW-1.3-e/f: symplectic Euler "destroys the left-right symmetry", Störmer–
    Verlet keeps it. ``se`` and ``sv``: the largest asymmetry over the cells of each method;
    ``growth_exponent_H`` and ``late_early_ratio_H``: the largest over the cells (metric growth)."""
    out: dict[str, float] = {}
    for row in cells.itertuples():
        key = {"symplectic-euler": "se", "stormer-verlet": "sv"}.get(row.base_method)
        if key is None:
            raise ValueError(f"asymmetry is for symplectic Euler and Störmer–Verlet, not {row.method}")
        rows = _rows(samples, row.cell)
        out[key] = max(out.get(key, 0.0), _asymmetry(rows["q"].to_numpy(dtype=float),
                                            rows["p"].to_numpy(dtype=float)))
    if "se" in out and "sv" in out:
        out["ratio"] = out["se"] / out["sv"] if out["sv"] > 0 else math.inf
    for name in ("growth_exponent_H", "late_early_ratio_H"):      # the energy, metric growth
        if name in cells:
            out[name] = float(cells[name].astype(float).max())
    return out


def _planets(rows, values):
    """Heliocentric positions and velocities of the five planets (bodies 1..5) at every sample."""
    q0 = rows[["q0x", "q0y", "q0z"]].to_numpy(dtype=float)
    v0 = rows[["p0x", "p0y", "p0z"]].to_numpy(dtype=float) / values["m0"]
    out = []
    for i in range(1, 6):
        q = rows[[f"q{i}x", f"q{i}y", f"q{i}z"]].to_numpy(dtype=float) - q0
        v = rows[[f"p{i}x", f"p{i}y", f"p{i}z"]].to_numpy(dtype=float) / values[f"m{i}"] - v0
        out.append((q, v))
    return out


def solar_system(cells, samples) -> dict:
    """[HLW] I.2.4, Fig 2.4, HLW-2.4-a…d, for the selected cells (the worst over them):
    ``energy_rise`` (err_H at the end, > 0: increasing energy), ``energy_monotone`` (share of
    positive increments of err_H), ``rel_energy`` (max |H − H0| / |H0|), ``energy_ratio``
    (max |err_H| over [T/2, T] / over [0, T/2]), ``jupiter_growth`` (r_J at the end / r_J(0)),
    ``js_min`` and ``js_start`` (Jupiter–Saturn distance: minimum and at t = 0), ``saturn_tilt``
    (largest angle in degrees between Saturn's heliocentric orbital normal and its initial one),
    ``a_dev`` (largest relative change of a planet's osculating semi-major axis, heliocentric
    two-body, 1/a = 2/r − v²/(G(m0 + m_i))), ``jupiter_fall``/``saturn_fall`` (first time the
    planet is within 0.5 AU of the sun, inf: never), ``final_r`` (smallest final distance of
    Jupiter and Saturn), ``t_final``; each also as ``<name>_<k>`` for the k-th selected cell alone
    (k = 0, 1, … in cell order), so that a claim on two methods can be judged method by method."""
    from gnibench.problems.codegen import python_functions
    from gnibench.suite.cell.spec import parse_problem

    worst: dict[str, float] = {}
    k = 0

    def keep(name, value, how=max):
        worst[name] = how(worst[name], value) if name in worst else value
        worst[f"{name}_{k}"] = value

    for k, row in enumerate(cells.itertuples()):
        problem = parse_problem(row.problem)
        values = dict(problem.values)
        rows = _rows(samples, row.cell)
        t = rows["t"].to_numpy(dtype=float)
        err = rows["err_H"].to_numpy(dtype=float)
        fns = python_functions(problem.record)
        H0 = float(fns["invariants"](tuple(problem.record.y0(problem.values)),
                                     problem.record.par(problem.values))[0])
        planets = _planets(rows, values)
        r = [np.linalg.norm(q, axis=1) for q, _ in planets]
        half = t <= t[-1] / 2
        late = float(np.max(np.abs(err[~half]))) if np.any(~half) else 0.0
        early = float(np.max(np.abs(err[half])))
        keep("energy_rise", float(err[-1]), min)
        keep("energy_monotone", float(np.mean(np.diff(err) > 0)), min)
        keep("rel_energy", float(np.max(np.abs(err)) / abs(H0)))
        keep("energy_ratio", late / early if early > 0 else 1.0)
        keep("jupiter_growth", float(r[0][-1] / r[0][0]), min)
        js = np.linalg.norm(planets[0][0] - planets[1][0], axis=1)
        keep("js_min", float(np.min(js)), min)
        keep("js_start", float(js[0]))
        normal = np.cross(*planets[1])
        normal /= np.linalg.norm(normal, axis=1)[:, None]
        tilt = np.degrees(np.arccos(np.clip(normal @ normal[0], -1.0, 1.0)))
        keep("saturn_tilt", float(np.max(tilt)), min)
        dev = 0.0
        for i, (q, v) in enumerate(planets, start=1):
            mu = values["G"] * (values["m0"] + values[f"m{i}"])
            a = 1.0 / (2.0 / np.linalg.norm(q, axis=1) - np.sum(v * v, axis=1) / mu)
            dev = max(dev, float(np.max(np.abs(a / a[0] - 1.0))))
        keep("a_dev", dev)
        for name, ri in (("jupiter_fall", r[0]), ("saturn_fall", r[1])):
            close = np.nonzero(ri < 0.5)[0]
            keep(name, float(t[close[0]]) if len(close) else math.inf)
        keep("final_r", float(min(r[0][-1], r[1][-1])), min)
        keep("t_final", float(t[-1]), min)
    return worst


def _implicit_euler_gap(rows, values, h: float) -> dict:
    """Why implicit Euler cannot take the step after the last sample of ``rows`` (a run that ended
    newton_failed): in relative coordinates r = q_J − q_S its equations read
    r1 + c r1/|r1|³ = r_pred + h² δ, c = h² G (m0 + m_J), r_pred = r + h (v_J − v_S), δ the pull of
    the other planets. The left side has the direction of r1 and the length g(|r1|), g(λ) = λ +
    c/λ², whose minimum over λ > 0 is g_min = (3/2)(2c)^{1/3} (at λ = (2c)^{1/3}); the right side
    is at most |r_pred| + h²|δ| long. So no r1 — no solution of the implicit Euler equations, for
    any solver — exists when ``margin`` = g_min − |r_pred| − h² δ_max > 0, with δ_max = G Σ m_k
    (1/(D_k − 2)² + 1/(D_k − 1)²) over the other planets at heliocentric distances D_k (each
    body moves far less than 1 AU in a step, and |r1| < g_min < 1 AU)."""
    q0 = rows[["q0x", "q0y", "q0z"]].to_numpy(dtype=float)[-1]
    v0 = rows[["p0x", "p0y", "p0z"]].to_numpy(dtype=float)[-1] / values["m0"]
    qJ = rows[["q1x", "q1y", "q1z"]].to_numpy(dtype=float)[-1]
    vJ = rows[["p1x", "p1y", "p1z"]].to_numpy(dtype=float)[-1] / values["m1"]
    G = values["G"]
    c = h * h * G * (values["m0"] + values["m1"])
    g_min = 1.5 * (2 * c) ** (1 / 3)
    r_pred = float(np.linalg.norm(qJ - q0 + h * (vJ - v0)))
    delta = 0.0
    for k in range(2, 6):
        D = float(np.linalg.norm(rows[[f"q{k}x", f"q{k}y", f"q{k}z"]].to_numpy(dtype=float)[-1] - q0))
        delta += G * values[f"m{k}"] * (1 / (D - 2) ** 2 + 1 / (D - 1) ** 2)
    return {"r_jupiter": float(np.linalg.norm(qJ - q0)), "r_predicted": r_pred, "g_min": g_min,
            "margin": g_min - r_pred - h * h * delta, "t_stop": float(rows["t"].iloc[-1])}


def implicit_euler_solar_system(cells, samples) -> dict:
    """[HLW] I.2.4, Fig 2.4, HLW-2.4-b: implicit Euler (h = 10) on the outer solar system. The
    selected cells are implicit Euler solved by Newton's method and by K fixed-point iterations
    (method option fixed_point = K, a sweep over K, which the seed does not give). For the
    Newton cell: whether it ended newton_failed and, at its last point, the ``margin`` of
    :func:`_implicit_euler_gap` (> 0: the step has no solution at all). For the fixed-point cells
    (each must run to the end): ``picture`` = share of them in which Jupiter comes within 0.5 AU
    of the sun before Saturn does and both end ≥ 50 AU away (the claims inventory), with each cell's
    ``jupiter_fall_<K>``, ``saturn_fall_<K>``, ``final_r_<K>``, ``unconverged_<K>`` (steps whose
    iteration did not converge, njev)."""
    from gnibench.suite.cell.spec import parse_method, parse_problem
    from gnibench.suite.ledger.reach import NotMeasured

    out: dict[str, float] = {}
    good, fixed = 0, 0
    for row in cells.itertuples():
        method = parse_method(row.method)
        if method.id != "implicit-euler" or method.modifiers:
            raise ValueError(f"select implicit Euler cells, not {row.method}")
        k = int(method.base.values.get("fixed_point", 0))
        if k == 0:
            out["newton_failed"] = float(row.status == "newton_failed")
            values = dict(parse_problem(row.problem).values)
            out.update(_implicit_euler_gap(_rows(samples, row.cell), values,
                                           float(method.base.values["h"])))
            continue
        if row.status != "ok":
            raise NotMeasured(f"the fixed-point cell {row.cell} ({row.method}) ended {row.status} "
                              f"at t = {row.t_final:.6g}")
        fixed += 1
        one = solar_system(cells[cells["cell"] == row.cell], samples)
        ok = one["jupiter_fall"] < one["saturn_fall"] and one["final_r"] >= 50
        good += ok
        for key in ("jupiter_fall", "saturn_fall", "final_r"):
            out[f"{key}_{k}"] = one[key]
        out[f"unconverged_{k}"] = float(row.njev)
    if "newton_failed" not in out or not fixed:
        raise LookupError("select the Newton cell and at least one fixed-point cell")
    out["picture"] = good / fixed
    out["measured"] = out["margin"]
    return out


def angular_momentum_roundoff(cells, samples) -> dict:
    """[HLW] I.2.3, HLW-2.1-b: the error of L = q1 p2 − q2 p1 against two round-off scales, over
    the selected cells (the worst): ``ratio_L`` = max|L_n − L0| / (ε |L0| √n) (the claims inventory's
    proposal) and ``ratio_qp`` = max|L_n − L0| / (ε max_n |q_n||p_n| √n): the products q1 p2 and
    q2 p1 are each rounded to ε |q||p|, which exceeds |L| by far near the pericentre at large h."""
    eps = float(np.finfo(float).eps)
    out = {"ratio_L": 0.0, "ratio_qp": 0.0, "err": 0.0}
    for row in cells.itertuples():
        rows = _rows(samples, row.cell)
        q = rows[["q1", "q2"]].to_numpy(dtype=float)
        p = rows[["p1", "p2"]].to_numpy(dtype=float)
        L0 = abs(q[0, 0] * p[0, 1] - q[0, 1] * p[0, 0])
        err = float(np.max(np.abs(rows["err_L"].to_numpy(dtype=float))))
        n = math.sqrt(max(float(row.steps), 1.0))
        qp = float(np.max(np.linalg.norm(q, axis=1) * np.linalg.norm(p, axis=1)))
        out["err"] = max(out["err"], err)
        out["ratio_L"] = max(out["ratio_L"], err / (eps * L0 * n))
        out["ratio_qp"] = max(out["ratio_qp"], err / (eps * qp * n))
    return out


CLOSED_FORMS = {
    "angular_momentum_roundoff": angular_momentum_roundoff,
    "lv_periodic": lv_periodic,
    "lv_stages": lv_stages,
    "pendulum_asymmetry": pendulum_asymmetry,
    "solar_system": solar_system,
    "implicit_euler_solar_system": implicit_euler_solar_system,
}
