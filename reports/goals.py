"""Accuracy goals: the fastest cell of each method family at each accuracy, against heyoka.

Issue 19's measure of the work-precision experiments (``wp-kepler-2d``, ``wp-outer-solar-system``):
for each accuracy ε, each family's fastest ``ok`` cell whose **final** global error is ≤ ε (no
interpolation: a cell that ran), its integration wall time and nfev; then the fastest *compiled*
family (``method_kind == "compiled"``: gnibench's kernels, not heyoka, IAS15 or scipy) against
heyoka's Taylor method in double precision and rebound's IAS15 in the same run(s).

Wall times of ~1 ms cells scatter on a loaded machine, so several runs of the same experiment
(``gnibench run … --fresh`` into separate directories) are combined: each cell's wall time is the
**median** over the runs (cells matched by problem and method spec; errors and nfev are
reproducible, taken from the first run). ``benchmarks/wp_goals.py`` prints the tables.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

GOAL_ACCURACIES = (1e-6, 1e-8, 1e-10, 1e-11, 1e-12, 1e-13)
HEYOKA = "heyoka-taylor"              # the double-precision family (long double is another family)
HEYOKA_LD = "heyoka-taylor:precision=long double"
IAS15 = "rebound-ias15"


@dataclass(frozen=True)
class Pick:
    """One family's fastest cell within an accuracy."""

    family: str
    method: str
    wall: float                       # seconds (median over the runs)
    nfev: float                       # NaN for engines that do not count
    error: float
    compiled: bool
    setting: str = ""                 # the swept option and its value, e.g. "rtol=1e-13"


def median_walls(runs) -> dict[tuple[str, str], float]:
    """(problem, method) -> the median integration wall time over ``runs`` (``Results``)."""
    walls: dict[tuple[str, str], list[float]] = {}
    for res in runs:
        t = res.timings
        for p, m, s, w in zip(t["problem"], t["method"], t["status"], t["wall_seconds"]):
            if s == "ok" and math.isfinite(w):
                walls.setdefault((str(p), str(m)), []).append(float(w))
    return {k: float(np.median(v)) for k, v in walls.items()}


def picks(cells, walls: dict[tuple[str, str], float], eps: float,
          column: str = "final_global_error") -> dict[str, Pick]:
    """family -> its fastest ok cell with ``column`` <= eps (families that reach eps only)."""
    out: dict[str, Pick] = {}
    for r in cells.itertuples(index=False):
        err = float(getattr(r, column))
        wall = walls.get((str(r.problem), str(r.method)), math.nan)
        if r.status != "ok" or not err <= eps or not math.isfinite(wall):
            continue
        best = out.get(r.family)
        if best is None or wall < best.wall:
            setting = f"{r.sweep}={r.sweep_value:.3g}" if r.sweep else ""
            out[r.family] = Pick(str(r.family), str(r.method), wall, float(r.nfev), err,
                                 str(r.method_kind) == "compiled", setting)
    return out


def best_errors(cells, column: str = "final_global_error") -> dict[str, float]:
    ok = cells[cells["status"] == "ok"]
    return {str(f): float(np.nanmin(p[column].to_numpy(dtype=float)))
            for f, p in ok.groupby("family", sort=False) if p[column].notna().any()}


def _ms(p: Pick | None, nfev: bool = True) -> str:
    if p is None:
        return "–"
    text = f"{p.wall * 1e3:.2f}"
    return text + (f" ({p.nfev:.0f})" if nfev and math.isfinite(p.nfev) else "")


def family_table(cells, walls, accuracies=GOAL_ACCURACIES, families=None,
                 column: str = "final_global_error") -> list[str]:
    """Markdown: one row per family, ms (nfev) of its fastest cell within each accuracy."""
    by_eps = [picks(cells, walls, eps, column) for eps in accuracies]
    best = best_errors(cells, column)
    fams = families or [f for f in dict.fromkeys(cells["family"]) if f in best]
    head = "| family | " + " | ".join(f"≤ {e:.0e}" for e in accuracies) + " | best final error |"
    lines = [head, "|" + "---|" * (len(accuracies) + 2)]
    for fam in fams:
        cols = [_ms(p.get(fam)) for p in by_eps]
        lines.append(f"| `{fam}` | " + " | ".join(cols) + f" | {best.get(fam, math.nan):.1e} |")
    return lines


def goal_rows(cells, walls, accuracies=GOAL_ACCURACIES, column: str = "final_global_error"):
    """Per accuracy: (eps, fastest compiled Pick, heyoka double Pick, IAS15 Pick, ratio of the
    compiled to heyoka's wall time, heyoka long double Pick)."""
    rows = []
    for eps in accuracies:
        p = picks(cells, walls, eps, column)
        compiled = [x for x in p.values() if x.compiled]
        fast = min(compiled, key=lambda x: x.wall) if compiled else None
        hey, ias = p.get(HEYOKA), p.get(IAS15)
        ratio = fast.wall / hey.wall if fast and hey else math.nan
        rows.append((eps, fast, hey, ias, ratio, p.get(HEYOKA_LD)))
    return rows


def goal_table(cells, walls, accuracies=GOAL_ACCURACIES,
               column: str = "final_global_error") -> list[str]:
    """Markdown: the fastest compiled cell, heyoka (double), IAS15 and the ratio per accuracy."""
    def cell(p: Pick | None) -> str:
        if p is None:
            return "none"
        nfev = f", {p.nfev:.0f} f-evals" if math.isfinite(p.nfev) else ""
        name = f"`{p.family}` " if p.compiled else ""
        return f"{name}{p.setting}: {p.wall * 1e3:.2f} ms{nfev} (error {p.error:.1e})"
    lines = [("| accuracy | fastest compiled | heyoka (double) | ratio to heyoka | IAS15 | "
              "heyoka (long double) |"), "|---|---|---|---|---|---|"]
    for eps, fast, hey, ias, ratio, ld in goal_rows(cells, walls, accuracies, column):
        r = f"{ratio:.2f}" if math.isfinite(ratio) else "–"
        lines.append(f"| ≤ {eps:.0e} | {cell(fast)} | {cell(hey)} | {r} | {cell(ias)} | "
                     f"{cell(ld)} |")
    return lines
