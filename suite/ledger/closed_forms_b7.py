"""Statistics of the so(4) section runs of [B] §7.2 (Figs 26-29), for the ledger's claims.

Registered beside the closed forms (:mod:`gnibench.suite.ledger.closed_forms`): each takes the
selected cells (rows of ``cells.parquet``) and the samples table and returns named values. The
samples of these runs are section crossings (``section = N``), so the ``growth`` metric, which
wants a trajectory, does not apply; the same statistics are computed here on the crossings.

* ``so4_overlap`` ([B] Fig 26, "the resemblance between both figures is exceptionally good";
  §7.2, "the shape of the obtained chaotic region is independent of the chosen initial orbit"):
  the points of each selected cell in the chart Γ1, binned on a 200 × 200 grid of
  (x5, x6) ∈ [−2, 2]² (claim B-7.2-b, proposed); the Jaccard overlap |A ∩ B| / |A ∪ B| of the
  occupied bins, the smallest over all pairs of cells; and the points in Γ1 of each cell.
* ``so4_plateau`` ([B] §7.2 after Fig 29, "oscillating around a stable non-zero value"): for each
  err_Hi, the least-squares line err = m + s t over [T/2, T], its drift |s|·T/2 relative to |mean|,
  |mean| / std (claim B-7.2-f), and ``same_sign``, the share of the samples in [T/2, T] with the
  sign of the mean: an error oscillating around zero has one sign half of the time, one that
  oscillates around a non-zero value more often; for a sinusoidal oscillation a + m, the share
  is ½ + arcsin(m/a)/π, so ``same_sign`` ≥ 3/4 ⇔ the offset m exceeds the oscillation's rms
  a/√2 (the claims inventory's |mean| ≥ 2 std instead demands an error that never changes sign). The worst
  over i and the cells.
* ``so4_growth`` ([B] §7.2, "the error ... increases for H1 and H2"): the growth exponent in t of
  the envelope max_{s≤t} |err_Hi(s)|, the least-squares slope of log envelope against log t over
  [T/100, T] on 200 log-spaced times (the claims inventory Conventions); the smallest over H1, H2 and cells.
"""
from __future__ import annotations

import itertools
import math

import numpy as np

GRID, BOX = 200, (-2.0, 2.0)


def _occupied(rows) -> set[int]:
    pts = rows[rows["chart"].to_numpy(dtype=float) == 1]
    x5, x6 = pts["x5"].to_numpy(dtype=float), pts["x6"].to_numpy(dtype=float)
    scale = GRID / (BOX[1] - BOX[0])
    i = np.clip(((x5 - BOX[0]) * scale).astype(int), 0, GRID - 1)
    j = np.clip(((x6 - BOX[0]) * scale).astype(int), 0, GRID - 1)
    return set((i * GRID + j).tolist())


def so4_overlap(cells, samples) -> dict:
    occupied, out = [], {}
    for k, row in enumerate(cells.sort_values("cell").itertuples()):
        rows = samples[samples["cell"] == row.cell]
        occupied.append(_occupied(rows))
        out[f"points_{k}"] = float((rows["chart"].to_numpy(dtype=float) == 1).sum())
    pairs = [len(a & b) / len(a | b) if a | b else math.nan
             for a, b in itertools.combinations(occupied, 2)]
    out["jaccard"] = float(min(pairs)) if pairs else math.nan
    out["occupied_min"] = float(min(len(a) for a in occupied))
    out["cells"] = float(len(occupied))
    return out


def _integrals(rows) -> list[str]:
    return [c[4:] for c in rows.columns if c.startswith("err_") and rows[c].notna().any()]


def so4_plateau(cells, samples) -> dict:
    drift, ratio, sign = 0.0, math.inf, math.inf
    out = {}
    for row in cells.itertuples():
        rows = samples[samples["cell"] == row.cell]
        t = rows["t"].to_numpy(dtype=float)
        late = t >= t[-1] / 2
        for name in _integrals(rows):
            e = rows[f"err_{name}"].to_numpy(dtype=float)[late]
            s = np.polyfit(t[late], e, 1)[0]
            mean, std = float(np.mean(e)), float(np.std(e))
            d = abs(s) * (t[-1] / 2) / abs(mean) if mean else math.inf
            r = abs(mean) / std if std else math.inf
            same = float(np.mean(np.sign(e) == np.sign(mean))) if mean else 0.0
            out[f"drift_{name}"], out[f"mean_over_std_{name}"] = d, r
            out[f"same_sign_{name}"] = same
            drift, ratio, sign = max(drift, d), min(ratio, r), min(sign, same)
    out["drift"], out["mean_over_std"], out["same_sign"] = drift, ratio, sign
    return out


def so4_growth(cells, samples) -> dict:
    out, worst = {}, math.inf
    for row in cells.itertuples():
        rows = samples[samples["cell"] == row.cell]
        t = rows["t"].to_numpy(dtype=float)
        grid = np.geomspace(t[-1] / 100, t[-1], 200)
        idx = np.clip(np.searchsorted(t, grid, side="right") - 1, 0, len(t) - 1)
        for name in ("H1", "H2"):
            env = np.maximum.accumulate(np.abs(rows[f"err_{name}"].to_numpy(dtype=float)))
            ok = env[idx] > 0
            slope = (np.polyfit(np.log(t[idx][ok]), np.log(env[idx][ok]), 1)[0]
                     if ok.sum() >= 2 else math.nan)
            out[f"exponent_{name}"] = float(slope)
            worst = min(worst, float(slope))
    out["exponent"] = worst
    return out


CLOSED_FORMS = {"so4_overlap": so4_overlap, "so4_plateau": so4_plateau, "so4_growth": so4_growth}
