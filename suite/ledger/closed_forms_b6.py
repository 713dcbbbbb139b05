"""The section points of the Gavrilov–Shil'nikov runs against the exact homoclinic trace, [B] §6.2.

On the section {p1 = 0, p2 > 0} ([B] §6.2) the transformation (6.2) at φ = π/2 gives
(q2, p2) = (−P, r) and q1 = K/p2, so 2(H − ωK) = q1² + q2² − p2² + p2⁴/2 there: the reduced
Hamiltonian (6.3). The exact orbit from (0, 0, 0, √2) lies on H = K = 0, whose trace is the curve
f(q2, p2) = q2² − p2² + p2⁴/2 = 0 (one lobe of the "figure 8" of Fig 15(a), the half q2 > 0 leading
into the equilibrium, the half q2 < 0 leading out). The modified system after Fig 23 has the trace
f = q2² − p2² + p2⁴/2 + B p2² q2² = 0 (its H at q1 = p1 = 0, times 2). The statistics below
measure the claims of the claims inventory §6 (B-6.2-a … B-6.2-q) on the section samples of each cell:

* ``points``; ``neg``/``pos``: points with q2 < 0 / q2 > 0 outside the disc ‖(q2, p2)‖ < 10⁻²;
* ``traversals``: passages from near the equilibrium (‖·‖ < 10⁻²) to the far tip (p2 > 1) of the loop;
* ``wrong``: points with q2 < 0 after the first point with q2 > 0 (the exact orbit has none);
* ``fraction``: the share of points with ‖(q2, p2)‖ < 10⁻³ ([B]: "almost 90%" for Fig 18);
* ``w``: the largest distance |f|/|∇f| from the exact trace of the points in ‖·‖ < 10⁻² (the
  transverse spread near the equilibrium); ``dmax``: the same over all points;
* ``closest``: min ‖(q2, p2)‖ over the second half of the points; ``decades``: log10(max/min) of
  the closest approaches of the completed passages near the equilibrium (after a far point and
  before a later one; 0 with fewer than two), shown for comparison only: it follows the drift of
  H and K (a run whose levels drift passes the equilibrium ever closer or farther), so it does
  not measure numerical chaos;
* **numerical chaos** (``irregular``, ``rho_max``, ``rho_median``, ``passages``): the closest
  approaches after the drift of H and K is removed. Near the saddle the reduced Hamiltonian (6.3)
  is, to leading order, H − ωI = (P² − r²)/2 + I²/(2r²) with I = K, so on the level
  E = H − ωK, I = K the smallest distance ‖(q2, p2)‖ = ‖(−P, r)‖ is reached where P = 0:
  d_min² = √(E² + I²) − E. An orbit moving on its level (the exact flow, or a run whose integrals
  drift slowly compared with one passage) passes the saddle as r² = d_min² cosh(2λ(t − t0))
  (λ = √ε = 1, the saddle's real eigenvalue), and the section points sample that passage at
  most T_c = 2π/ω apart (one rotation), so the closest point of a passage k lies within
  ρ_k = log10(d_k / d_min(E_k, I_k)) ∈ [0, s], s = ½ log10 cosh(λ T_c) = 0.094 decade, of its
  own level's minimum, E_k and I_k evaluated at that very point (the drift is thereby removed:
  whatever the levels, a regular passage stays within s). A passage with ρ_k > s turned away at
  a distance its level does not allow: the levels changed during the passage — the irregular
  behaviour [B] calls numerical chaos. ``irregular`` = share of the passages with ρ_k > s;
  regular: none (0); chaotic: the rule (≥ 1/2, a majority); partly irregular in between
  (thresholds fixed by this argument, not by the runs; claim B-6.2-b proposed "irregular
  order" without a number). (The bound assumes the crossings of the section every T_c or more
  often, true while ω + I/r² ≥ ω, i.e. I ≥ 0 near the passage; we do not correct for I < 0.)
* ``increases``: steps along the points after the last far point (p2 > 1) where ‖·‖ grows by more
  than 1 % (a monotone approach has none);
* ``spread_H``, ``spread_K``: max − min of H − H0 and K − K0 over the second half of the points
  (points of one invariant curve share one level);
* ``err_H_100``, ``err_K_100``: |H − H0|, |K − K0| at the 100th point;
* ``p1_max``, ``p1_near``: the largest |p1| at the located points, over all of them and over
  ‖·‖ < 10⁻² (zero to round-off by construction: Hénon's trick integrates in p1 itself; [B]'s
  "position of points on the section was determined with precision higher than 10⁻¹⁵", B-6.2-q,
  is measured against an independent location, closed_forms_locator.py).

With one selected cell the names are as above; with several, each cell's values are also named
``<stat>_<label>`` with its group label in lower case, non-alphanumerics replaced by ``_``.
"""
from __future__ import annotations

import math
import re

import numpy as np

NEAR, FAR, SMALL = 1e-2, 1.0, 1e-3
#: the sampling bound of a regular passage: ½ log10 cosh(λ T_c), λ = √ε = 1, T_c = 2π/ω = 1
SAMPLING_BOUND = 0.5 * math.log10(math.cosh(1.0))


def _trace(problem: str, q2: np.ndarray, p2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """f and |∇f| of the exact trace H = K = 0 on the section, (q2, p2) coordinates."""
    from gnibench.suite.cell.spec import parse_problem

    bound = parse_problem(problem)
    B = float(bound.values.get("B", 0.0)) if bound.record.id == "gavrilov-shilnikov-modified" \
        else 0.0
    f = q2**2 - p2**2 + p2**4 / 2 + B * p2**2 * q2**2
    fq = 2 * q2 + 2 * B * p2**2 * q2
    fp = -2 * p2 + 2 * p2**3 + 2 * B * p2 * q2**2
    return f, np.hypot(fq, fp)


def _passages(near: np.ndarray, far: np.ndarray) -> list[tuple[int, int]]:
    """[start, end) of the completed passages: runs of consecutive near points that come after a
    far point (not the first approach from the start) and end before the last point."""
    runs, start = [], None
    first = int(np.argmax(far)) if far.any() else len(near)
    for i, v in enumerate(near):
        if i < first:
            continue
        if v and start is None:
            start = i
        elif not v and start is not None:
            runs.append((start, i))
            start = None
    return runs


def _levels(problem: str, rows, idx: list[int]) -> tuple[np.ndarray, np.ndarray]:
    """E = H − ωK and I = K at the rows idx, evaluated from the state (accurate near 0)."""
    from gnibench.problems.codegen import problem_meta, python_functions
    from gnibench.suite.cell.spec import parse_problem

    bound = parse_problem(problem)
    fns = python_functions(bound.record)
    par = bound.record.par(bound.values)
    names = problem_meta(bound.record)["integrals"]
    Y = rows[list(bound.record.state)].to_numpy(float)
    E, I = [], []
    for k in idx:
        vals = fns["invariants"](tuple(Y[k]), par)
        H, K = vals[names.index("H")], vals[names.index("K")]
        E.append(H - bound.values["omega"] * K)
        I.append(K)
    return np.array(E, dtype=float), np.array(I, dtype=float)


def chaos_stats(problem: str, rows, r: np.ndarray, runs) -> dict:
    """``irregular``, ``rho_max``, ``rho_median``, ``passages`` (module docstring)."""
    if not runs:
        return {"irregular": 0.0, "rho_max": 0.0, "rho_median": 0.0, "passages": 0.0}
    idx = [a + int(np.argmin(r[a:b])) for a, b in runs]
    E, I = _levels(problem, rows, idx)
    with np.errstate(all="ignore"):
        dmin = np.sqrt(np.sqrt(E * E + I * I) - E)
        rho = np.log10(r[idx] / dmin)
    rho = np.where(np.isfinite(rho), rho, np.inf)     # a level with d_min = 0: turned at d > 0
    return {"irregular": float(np.mean(rho > SAMPLING_BOUND)), "rho_max": float(np.max(rho)),
            "rho_median": float(np.median(rho)), "passages": float(len(idx))}


def cell_stats(problem: str, rows) -> dict:
    """The statistics of the module docstring for one cell's section samples."""
    q2, p2 = rows["q2"].to_numpy(float), rows["p2"].to_numpy(float)
    eH, eK = rows["err_H"].to_numpy(float), rows["err_K"].to_numpy(float)
    p1 = rows["p1"].to_numpy(float)
    n = len(q2)
    r = np.hypot(q2, p2)
    near = r < NEAR
    f, grad = _trace(problem, q2, p2)
    with np.errstate(all="ignore"):
        d = np.where(grad > 0, np.abs(f) / grad, r)
    far = p2 > FAR
    traversals, was_near = 0, False
    for is_near, is_far in zip(near, far):
        if is_far and was_near:
            traversals += 1
        was_near = (was_near or is_near) and not is_far
    first_pos = int(np.argmax(q2 > 0)) if np.any(q2 > 0) else n
    runs = _passages(near, far)
    closest = [float(np.min(r[a:b])) for a, b in runs]
    positive = [c for c in closest if c > 0]
    last_far = int(np.nonzero(far)[0][-1]) + 1 if far.any() else 0
    tail = r[last_far:]
    half = slice(n // 2, n)
    k100 = min(99, n - 1)
    return {
        **chaos_stats(problem, rows, r, runs),
        "points": float(n),
        "neg": float(np.sum((q2 < 0) & ~near)), "pos": float(np.sum((q2 > 0) & ~near)),
        "traversals": float(traversals),
        "wrong": float(np.sum(q2[first_pos:] < 0)),
        "fraction": float(np.mean(r < SMALL)) if n else math.nan,
        "w": float(np.max(d[near])) if near.any() else 0.0,
        "dmax": float(np.max(d)) if n else math.nan,
        "closest": float(np.min(r[half])) if n else math.nan,
        "decades": float(math.log10(max(positive) / min(positive))) if len(positive) >= 2 else 0.0,
        "increases": float(np.sum(tail[1:] > 1.01 * tail[:-1])),
        "spread_H": float(np.ptp(eH[half])) if n else math.nan,
        "spread_K": float(np.ptp(eK[half])) if n else math.nan,
        "err_H_100": float(abs(eH[k100])) if n else math.nan,
        "err_K_100": float(abs(eK[k100])) if n else math.nan,
        "p1_max": float(np.max(np.abs(p1))) if n else math.nan,
        "p1_near": float(np.max(np.abs(p1[near]))) if near.any() else 0.0,
    }


def slug(label: str) -> str:
    return re.sub(r"[^a-z0-9]+", "_", str(label).lower()).strip("_")


def per_cell(cells, stats) -> dict:
    """``stats(row)`` of every selected cell: its names as they are for one cell, suffixed by the
    cell's label (:func:`slug`) for several; and ``cells``, their number."""
    out: dict = {}
    for row in cells.itertuples():
        s = stats(row)
        out.update(s if len(cells) == 1 else {f"{k}_{slug(row.label)}": v for k, v in s.items()})
    out["cells"] = float(len(cells))
    return out


def gs_section_trace(cells, samples) -> dict:
    """The statistics of every selected cell (see the module docstring)."""
    return per_cell(cells, lambda row: cell_stats(row.problem,
                                                  samples[samples["cell"] == row.cell]))
