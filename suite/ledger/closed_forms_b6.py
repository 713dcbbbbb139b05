"""The section points of the Gavrilov–Shil'nikov runs against the exact homoclinic trace, [B] §6.2.

On the section {p1 = 0, p2 > 0} ([B] §6.2) the transformation (6.2) at φ = π/2 gives
(q2, p2) = (−P, r) and q1 = K/p2, so 2(H − ωK) = q1² + q2² − p2² + p2⁴/2 there: the reduced
Hamiltonian (6.3). The exact orbit from (0, 0, 0, √2) lies on H = K = 0, whose trace is the curve
f(q2, p2) = q2² − p2² + p2⁴/2 = 0 (one lobe of the "figure 8" of Fig 15(a), the half q2 > 0 leading
into the equilibrium, the half q2 < 0 leading out). The modified system after Fig 23 has the trace
f = q2² − p2² + p2⁴/2 + B p2² q2² = 0 (its H at q1 = p1 = 0, times 2). The statistics below
measure the claims of CLAIMS.md §6 (B-6.2-a … B-6.2-q) on the section samples of each cell:

* ``points``; ``neg``/``pos``: points with q2 < 0 / q2 > 0 outside the disc ‖(q2, p2)‖ < 10⁻²;
* ``traversals``: passages from near the equilibrium (‖·‖ < 10⁻²) to the far tip (p2 > 1) of the loop;
* ``wrong``: points with q2 < 0 after the first point with q2 > 0 (the exact orbit has none);
* ``fraction``: the share of points with ‖(q2, p2)‖ < 10⁻³ ([B]: "almost 90%" for Fig 18);
* ``w``: the largest distance |f|/|∇f| from the exact trace of the points in ‖·‖ < 10⁻² (the
  transverse spread near the equilibrium); ``dmax``: the same over all points;
* ``closest``: min ‖(q2, p2)‖ over the second half of the points; ``decades``: log10(max/min) of
  the closest approaches of the completed passages near the equilibrium (after a far point and
  before a later one; 0 with fewer than two);
* ``increases``: steps along the points after the last far point (p2 > 1) where ‖·‖ grows by more
  than 1 % (a monotone approach has none);
* ``spread_H``, ``spread_K``: max − min of H − H0 and K − K0 over the second half of the points
  (points of one invariant curve share one level);
* ``err_H_100``, ``err_K_100``: |H − H0|, |K − K0| at the 100th point;
* ``p1_max``, ``p1_near``: the largest |p1| at the located points, over all of them and over
  ‖·‖ < 10⁻² ([B]: "position of points on the section was determined with precision higher than
  10⁻¹⁵").

With one selected cell the names are as above; with several, each cell's values are also named
``<stat>_<label>`` with its group label in lower case, non-alphanumerics replaced by ``_``.
"""
from __future__ import annotations

import math
import re

import numpy as np

NEAR, FAR, SMALL = 1e-2, 1.0, 1e-3


def _trace(problem: str, q2: np.ndarray, p2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """f and |∇f| of the exact trace H = K = 0 on the section, (q2, p2) coordinates."""
    from gnibench.suite.cell.spec import parse_problem

    values = parse_problem(problem).values
    B = float(values.get("B", 0.0)) if problem.startswith("gavrilov-shilnikov-modified") else 0.0
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


def gs_section_trace(cells, samples) -> dict:
    """The statistics of every selected cell (see the module docstring)."""
    out: dict = {}
    stats = []
    for row in cells.itertuples():
        rows = samples[samples["cell"] == row.cell]
        s = cell_stats(row.problem, rows)
        stats.append(s)
        if len(cells) > 1:
            out.update({f"{k}_{slug(row.label)}": v for k, v in s.items()})
    if len(stats) == 1:
        out.update(stats[0])
    out["cells"] = float(len(cells))
    return out
