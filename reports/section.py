"""One problem's section of an experiment page, as plain data: its time plots, then per context
(one horizon and reference, :func:`gnibench.reports.setups.contexts`) the work-precision diagram
(a PNG and its interactive twin) and the league tables, then the table of cells.
"""
from __future__ import annotations

import math
from pathlib import Path

from gnibench.reports import ensembles, interactive, plots, workprecision
from gnibench.reports.palette import Palette, styles
from gnibench.reports.setups import context_rows, family_names


def repeats_words(stats: dict, ids) -> str:
    """How the wall times of the cells ``ids`` were measured, in words."""
    runs = sorted({stats[c][3] for c in ids if c in stats and stats[c][3] > 0})
    if not runs or runs == [1]:
        return "one run per cell"
    what = f"{runs[0]}" if len(runs) == 1 else f"{runs[0]} to {runs[-1]}"
    return (f"the fastest of {what} runs per cell (median and spread in the table of cells and on "
            f"hover)")


def swept_contexts(cells) -> set[str]:
    """The contexts (column ``context``) in which some family has two or more cells, in one pass
    (:func:`gnibench.reports.workprecision.has_sweeps` of each context's cells)."""
    sizes = cells.groupby(["context", "setup"], sort=False).size()
    return {c for (c, _), n in sizes.items() if n >= 2}


def problem_section(problem: str, part, samples, img_dir: Path, prefix: str, slug: str, jobs,
                    res, thresholds, palette: Palette, options: dict) -> dict:
    """The content of one problem's section (``part``: its cells, with the columns of
    :func:`gnibench.reports.setups.add_setups`); its figures' drawing is appended to ``jobs``."""
    from gnibench.reports.tables import cells_table, league_tables

    stats = res.wall_stats()
    wall = {c: v[0] for c, v in stats.items()}
    t = res.timings
    compile_s = {int(c): float(v) for c, v in zip(t["cell"], t["compile_seconds"])} if len(t) else {}
    kinds = options.get("figures") or ("invariants", "global-error", "eta", "sections",
                                       "work-precision", "league")
    style = styles(part, palette)
    names = family_names(part)
    by_cell = plots.trajectories(samples) if samples is not None else None
    memo: dict = {}
    figs = plots.time_figures(problem, part, samples, img_dir, prefix, slug, jobs, by_cell, memo,
                              style, names, options) \
        if samples is not None and len(samples) else []
    words = repeats_words(stats, [int(c) for c in part["cell"]])
    out_contexts = []
    curves = swept_contexts(part)
    for k, (key, name, rows) in enumerate(context_rows(part)):
        if key not in curves:          # no family with two cells: no diagram, no league table
            continue
        ctx = part.iloc[rows]
        cnames = family_names(ctx)
        wp, live = [], None
        if "work-precision" in kinds:
            cprefix = prefix if k == 0 else f"{prefix}-{k}"
            wp = workprecision.wp_figures(problem, ctx, {c: w * 1e3 for c, w in wall.items()},
                                          img_dir, cprefix, slug, jobs, style, cnames, options,
                                          name, words)
            doc = interactive.wp_figure_json(wp[0].title if wp else problem, ctx, stats, style,
                                             cnames, options) if wp else None
            if doc is not None:
                live = {"id": f"wp-{slug}-{cprefix}", "json": interactive.script_json(doc)}
        league = league_tables(ctx, wall, thresholds, cnames) if "league" in kinds else {}
        if wp or league:
            out_contexts.append({
                "name": name, "wp": [f.__dict__ for f in wp], "interactive": live,
                "no_nfev": workprecision.no_nfev(ctx, cnames) if wp else [], "league": league,
                "headline": headline(ctx, wall, cnames, options.get("target") or min(thresholds),
                                     name)})
    failed = [{"cell": str(r.cell), "method": str(r.method), "status": str(r.status),
               "reason": str(r.reason or "")} for r in part.itertuples() if r.status != "ok"]
    groups = [{"group": str(g), "label": str(lab or "")} for g, lab in
              part[["group", "label"]].drop_duplicates().itertuples(index=False)]
    return {"name": str(problem), "anchor": prefix, "figures": [f.__dict__ for f in figs],
            "contexts": out_contexts, "repeats": words,
            "ensemble": ensembles.section(res, part, img_dir, prefix, slug, thresholds, jobs,
                                          palette=palette),
            "table": cells_table(part, samples, stats, compile_s, by_cell, memo, names),
            "failed": failed, "groups": groups}


def headline(ctx, wall: dict[int, float], names: dict, target: float, context: str) -> dict:
    """The cheapest family of a context to reach ``target`` in its league measure: {"text",
    "rank"} ("rank" False when no family reaches it or nothing can be ranked)."""
    from gnibench.reports import league
    from gnibench.reports.tables import num

    column, words = league.accuracy_column(ctx)
    if not column:
        return {"text": "", "rank": False}
    where = f" ({context})" if context else ""
    why = league.unrankable(ctx, column, target)
    if why:
        return {"text": f"{column} ≤ {target:.0e}{where}: {why}", "rank": False}
    rows = league.league(ctx, wall, target, column, names)
    best = next((r for r in rows if r.rank_nfev == 1), None) or \
        next((r for r in rows if r.rank_wall == 1), None)
    if best is None:
        finite = [r for r in rows if math.isfinite(r.best_error)]
        closest = min(finite, key=lambda r: r.best_error) if finite else None
        tail = f" (closest: {closest.family}, {num(closest.best_error)})" if closest else ""
        return {"text": f"no method reaches {column} ≤ {target:.0e}{where}{tail}",
                "rank": False}
    cost = (f"{num(best.nfev.value, '.3g')} f-evaluations" if best.rank_nfev == 1
            else f"{num(best.wall.value * 1e3, '.3g')} ms")
    return {"text": f"cheapest to reach {column} ≤ {target:.0e}{where}: {best.family}, {cost}",
            "rank": True}
