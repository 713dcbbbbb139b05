"""The claims ledger as Markdown, from ``ledger.parquet`` only (it never integrates).

One table per section of the seeds: the claim in our words, the verdict (and the expected one
when they differ), the measured number beside the seed's, whether the threshold is the seed's or
ours, the doubtful reading used, and the link to the figure.
"""
from __future__ import annotations

import pandas as pd
from gnibench.reports.markdown import code, escape

VERDICT_ORDER = ("reproduced", "partly", "not reproduced", "not checkable")


def section(claim_id: str) -> str:
    """``B-4.2-d`` -> ``[B] §4.2``; ``HLW-2.1-table-H-EE`` -> ``[HLW] Table 2.1``."""
    seed, _, rest = claim_id.partition("-")
    part = rest.rsplit("-", 1)[0]
    if "table" in rest:
        return f"[{seed}] Table {rest.split('-table')[0]}"
    if part in ("X",):
        return f"[{seed}] cross-cutting"
    return f"[{seed}] §{part}" if seed == "B" else f"[{seed}] I.{part}"


def render_ledger(table: pd.DataFrame, meta: dict) -> str:
    counts = table["verdict"].value_counts()
    lines = ["# Claims ledger: [B] and [HLW] Ch. I against our measurements", ""]
    scale = meta.get("scale", "")
    lines.append(f"{len(table)} claims at the {escape(scale)} scale: "
                 + ", ".join(f"{counts.get(v, 0)} {v}" for v in VERDICT_ORDER) + ".")
    unexpected = table[table["unexpected"]]
    if len(unexpected):
        lines.append("")
        lines.append(f"**{len(unexpected)} verdicts differ from the expected ones:** "
                     + ", ".join(code(i) for i in unexpected["id"]) + ".")
    lines += ["", ("Verdicts: *reproduced* (the pass criterion holds), *not reproduced* (it does not, "
              "with the numbers), *partly* (a weaker criterion holds, or the verdict depends on a "
              "parameter the seed leaves open), *not checkable* (with the reason). The threshold is "
              "the seed's own number (*seed*) or proposed in CLAIMS.md (*proposed*), or a closed "
              "form derived from the method's map."), ""]
    for name, part in table.groupby(table["id"].map(section), sort=False):
        lines += [f"## {escape(name)}", "",
                  "| claim | verdict | measured | seed | threshold | figure |",
                  "|---|---|---|---|---|---|"]
        for r in part.itertuples():
            verdict = f"**{r.verdict}**"
            if r.verdict != r.expected:
                verdict += f" (expected: {r.expected})"
            claim = f"{code(r.id)} {escape(r.citation)}: {escape(r.claim)}"
            if r.reading:
                claim += f" *Reading:* {escape(r.reading)}"
            measured = escape(r.measured_text)
            if r.detail:
                measured += f" — {escape(r.detail)}"
            if r.sweep:
                measured += f" — {escape(r.sweep)}"
            figure = code(r.figure) if r.figure else ""
            lines.append(f"| {claim} | {verdict} | {measured} | {escape(r.seed_value)} | "
                         f"{escape(r.threshold)} | {figure} |")
        lines.append("")
    return "\n".join(lines)


def ledger_context(table: pd.DataFrame, meta: dict, pages: set[str]) -> dict:
    """What the HTML ledger page shows: counts, and per section of the seeds the claims with
    verdict, measured and seed values, threshold, reading, and a link to the figure's page when
    the site holds it (``pages``: the experiment slugs of the site)."""
    counts = table["verdict"].value_counts()
    sections = []
    for name, part in table.groupby(table["id"].map(section), sort=False):
        rows = []
        for r in part.itertuples():
            measured = str(r.measured_text)
            extra = [str(x) for x in (r.detail, r.sweep) if x]
            rows.append({"id": r.id, "citation": r.citation, "claim": r.claim,
                         "reading": r.reading or "", "verdict": r.verdict,
                         "expected": r.expected, "unexpected": bool(r.unexpected),
                         "measured": measured, "extra": extra, "seed": r.seed_value,
                         "threshold": r.threshold, "figure": r.figure or "",
                         "figure_href": f"{r.figure}.html" if r.figure in pages else ""})
        sections.append({"name": name, "rows": rows})
    return {"scale": meta.get("scale", ""), "total": len(table),
            "counts": [(v, int(counts.get(v, 0))) for v in VERDICT_ORDER],
            "unexpected": [str(i) for i in table.loc[table["unexpected"], "id"]],
            "sections": sections}
