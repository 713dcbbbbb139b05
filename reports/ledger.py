"""The claims ledger as Markdown and as the context of its HTML page, from ``ledger.parquet`` only
(it never integrates), and the mutation score from ``mutants.json`` beside it when there is one.

One table per section of the seeds: the claim in our words, the verdict, the measured number beside
the seed's, whether the threshold is the seed's or ours, the doubtful reading used, the runs the
verdict read (status and reach: final t, steps, section points), and for a claim not reproduced
the failing conditions, the closest point of our sweep and what would have been needed. The
``expected`` verdicts are a regression record of our own earlier outcome, not evidence: the page
says where a verdict differs from it, never that agreement with it supports a claim.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import pandas as pd
from gnibench.reports.markdown import code, escape
from gnibench.suite.ledger.verdicts import VERDICT_ORDER

VERDICTS_TEXT = (
    "Verdicts: *reproduced* (the pass criterion holds), *partly* (a weaker criterion holds, or the "
    "verdict differs across a parameter the seed leaves open), *not reproduced* (it does not, with "
    "the numbers; also when a run it needs stopped early or a value was read where the run did "
    "not get: *not measured*, with where the run stopped), *not checkable* (not a computation, or "
    "a method of another work in whose place we run ours; with the reason), *skipped* (paper "
    "scale only), *error* (the measurement itself failed). The threshold is the seed's own number "
    "(*seed*), proposed in the claims inventory (*proposed*), or a closed form derived from the method's map. "
    "The expected verdicts are a regression record of our own earlier outcome, not evidence: "
    "agreeing with them says nothing about the seeds.")


def section(claim_id: str) -> str:
    """``B-4.2-d`` -> ``[B] §4.2``; ``HLW-2.1-table-H-EE`` -> ``[HLW] Table 2.1``;
    ``B-3-b.corrected`` -> ``[B] §3``."""
    seed, _, rest = claim_id.removesuffix(".corrected").partition("-")
    part = rest.rsplit("-", 1)[0]
    if "table" in rest:
        return f"[{seed}] Table {rest.split('-table')[0]}"
    if part in ("X",):
        return f"[{seed}] cross-cutting"
    return f"[{seed}] §{part}" if seed == "B" else f"[{seed}] I.{part}"


def _col(r, name: str) -> str:
    value = getattr(r, name, "")
    return "" if value is None or (isinstance(value, float) and math.isnan(value)) else str(value)


def _extras(r) -> list[tuple[str, str]]:
    """(label, text) lines under the measured value: detail, sweep, why not reproduced."""
    out = []
    for label, name in (("", "detail"), ("sweep", "sweep"), ("fails", "failing"),
                        ("closest point of our sweep", "closest"),
                        ("would have needed", "needed")):
        text = _col(r, name)
        if not text or (name == "needed" and r.verdict == "reproduced"):
            continue
        if name in ("failing", "closest") and r.verdict == "reproduced":
            continue
        out.append((label, text))
    return out


def mutation_summary(directory: Path | None) -> dict | None:
    """The mutation score of ``mutants.json`` in ``directory`` (gnibench verify --mutants)."""
    if directory is None or not (Path(directory) / "mutants.json").is_file():
        return None
    try:
        doc = json.loads((Path(directory) / "mutants.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    rows = doc.get("mutants", [])
    survivors = [m for m in rows if not m.get("killed")]
    return {"total": len(rows), "killed": len(rows) - len(survivors), "scale": doc.get("scale", ""),
            "score": doc.get("score"), "survivors": survivors, "mutants": rows,
            "date": doc.get("date", ""), "planned": doc.get("planned", len(rows))}


def render_ledger(table: pd.DataFrame, meta: dict, mutants: dict | None = None) -> str:
    counts = table["verdict"].value_counts()
    lines = ["# Claims ledger: [B] and [HLW] Ch. I against our measurements", ""]
    scale = meta.get("scale", "")
    lines.append(f"{len(table)} claims at the {escape(scale)} scale: "
                 + ", ".join(f"{counts.get(v, 0)} {v}" for v in VERDICT_ORDER) + ".")
    unexpected = table[table["unexpected"]]
    if len(unexpected):
        lines.append("")
        lines.append(f"**{len(unexpected)} verdicts differ from the regression record (or failed "
                     "to measure):** " + ", ".join(code(i) for i in unexpected["id"]) + ".")
    lines += ["", VERDICTS_TEXT, ""]
    if mutants:
        when = f", {escape(mutants['date'])}" if mutants.get("date") else ""
        lines.append(f"**Mutation testing** ({escape(mutants['scale'])} scale{when}): "
                     f"{mutants['killed']} of {mutants['total']} mutants of the integrators and "
                     "metrics killed by the ledger or the tests."
                     + (f" The run was interrupted: {mutants['planned'] - mutants['total']} of the "
                        f"{mutants['planned']} mutants it was asked for did not run."
                        if mutants.get("planned", 0) > mutants["total"] else ""))
        for m in mutants["survivors"]:
            lines.append(f"* survived: {code(m['id'])} — {escape(m.get('description', ''))}"
                         + (f" ({escape(m['blind_spot'])})" if m.get("blind_spot") else ""))
        lines.append("")
    for name, part in table.groupby(table["id"].map(section), sort=False):
        lines += [f"## {escape(name)}", "",
                  "| claim | verdict | measured | seed | threshold | runs | figure |",
                  "|---|---|---|---|---|---|---|"]
        for r in part.itertuples():
            verdict = f"**{r.verdict}**"
            if _col(r, "not_measured"):
                verdict += " (not measured)"
            if r.unexpected:
                verdict += f" (regression record: {escape(r.expected)})"
            claim = f"{code(r.id)} {escape(r.citation)}: {escape(r.claim)}"
            if r.reading:
                claim += f" *Reading:* {escape(r.reading)}"
            measured = escape(r.measured_text)
            for label, text in _extras(r):
                measured += f" — {('*' + label + ':* ') if label else ''}{escape(text)}"
            runs = "<br>".join(escape(x) for x in _col(r, "runs").splitlines())
            figure = code(r.figure) if r.figure else ""
            lines.append(f"| {claim} | {verdict} | {measured} | {escape(r.seed_value)} | "
                         f"{escape(r.threshold)} | {runs} | {figure} |")
        lines.append("")
    return "\n".join(lines)


def ledger_context(table: pd.DataFrame, meta: dict, pages: set[str],
                   mutants: dict | None = None) -> dict:
    """What the HTML ledger page shows: counts, and per section of the seeds the claims with
    verdict, measured and seed values, threshold, reading, the runs read (status and reach), why
    a claim is not reproduced, and a link to the figure's page when the site holds it (``pages``:
    the experiment slugs of the site); the mutation score when ``mutants`` is given."""
    counts = table["verdict"].value_counts()
    sections = []
    for name, part in table.groupby(table["id"].map(section), sort=False):
        rows = []
        for r in part.itertuples():
            rows.append({"id": r.id, "citation": r.citation, "claim": r.claim,
                         "reading": r.reading or "", "verdict": r.verdict,
                         "not_measured": bool(_col(r, "not_measured")),
                         "expected": r.expected, "unexpected": bool(r.unexpected),
                         "measured": str(r.measured_text), "extra": _extras(r),
                         "runs": _col(r, "runs").splitlines(),
                         "runs_complete": bool(getattr(r, "runs_complete", True)),
                         "seed": r.seed_value, "threshold": r.threshold,
                         "figure": r.figure or "",
                         "figure_href": f"{r.figure}.html" if r.figure in pages else ""})
        sections.append({"name": name, "rows": rows})
    return {"scale": meta.get("scale", ""), "total": len(table),
            "counts": [(v, int(counts.get(v, 0))) for v in VERDICT_ORDER],
            "unexpected": [str(i) for i in table.loc[table["unexpected"], "id"]],
            "verdicts_text": VERDICTS_TEXT, "mutants": mutants, "sections": sections}
