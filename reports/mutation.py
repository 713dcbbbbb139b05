"""Mutation campaigns as Markdown: the tables of the docs' page on mutation testing.

A campaign of ``gnibench verify --mutants`` writes ``mutants.json`` (:mod:`gnibench.suite.ledger.
mutants`); the ones the project keeps are saved under ``benchmarks/`` as
``mutants-<date>.json`` (the shipped catalog) and ``mutants-<set>-<machinery>-<date>.json``
(held-out sets). These functions only read them: :func:`campaigns` lists them, :func:`score_line`
states a campaign's score with its date, commit and what ran against each mutant, and
:func:`mutant_table` gives one row per mutant (what killed it, or why it is a blind spot).
``benchmarks/mutation/cosmic-ray-<date>.json`` (the cosmic-ray campaign,
benchmarks/mutation/README.md) is read by :func:`cosmic_ray_table`.
"""
from __future__ import annotations

import json
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]          # the package root: benchmarks/ beside reports/


def campaigns(pattern: str = "mutants-*.json", root: Path | None = None) -> list[Path]:
    """The saved campaigns matching ``pattern`` under ``benchmarks/``, oldest first (by the date
    in the name)."""
    found = sorted((root or ROOT / "benchmarks").glob(pattern))
    return sorted(found, key=lambda p: (re.findall(r"\d{4}-\d{2}-\d{2}", p.name) or [""])[-1])


def load(path: Path | str) -> dict:
    return json.loads(Path(path).read_text(encoding="utf-8"))


def _cell(text: str) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def score_line(doc: dict) -> str:
    """The score, when and on which commit it was measured, and what ran against each mutant."""
    tests = doc.get("tests")
    if isinstance(tests, list):
        ran = f"the ledger and a hand-kept list of {len(tests)} test files"
    elif tests == "all":
        ran = "the ledger and the complete test suite"
    elif tests == "none":
        ran = "the ledger only"
    else:
        ran = "the ledger and every test file whose imports reach the mutated file"
    commit = (doc.get("commit") or "unrecorded")[:10]
    done = "" if doc.get("complete", True) else \
        f" (interrupted: {doc['total']} of {doc.get('planned', '?')} mutants)"
    open_ = sum(bool(row.get("inconclusive")) for row in doc.get("mutants", []))
    unsettled = f", {open_} inconclusive (time limit)" if open_ else ""
    return (f"**{doc['killed']} of {doc['total']} killed** ({100 * doc['killed'] / doc['total']:.0f} %"
            f"{unsettled}) on {doc.get('date', '?')}, commit {commit}, at the "
            f"{doc.get('scale', '?')} scale, with {ran}{done}.")


def _killer(row: dict) -> str:
    found = [f"claim {c}" for c in row.get("claims", [])[:2]]
    found += [f"`{t.split('[')[0]}`" for t in row.get("tests", [])[:1]]
    if not found and row.get("crash"):
        found = ["the ledger run failing (" + re.sub(r"^.*: ", "", row["crash"])[:80] + ")"]
    if not found and row.get("timeout"):
        found = ["a time limit"]
    return ", ".join(found)


def blind_spots() -> dict[str, str]:
    """Why each known survivor of the shipped catalog survives (its entries' ``blind_spot``)."""
    from gnibench.suite.ledger.mutants import load_catalog

    return {m.id: m.blind_spot for m in load_catalog()[0] if m.blind_spot}


def mutant_table(doc: dict) -> str:
    """One row per mutant: id, file, what the bug does, and what killed it (or why it survived:
    the campaign's record of the catalog entry's ``blind_spot``, else the catalog's now)."""
    lines = ["| mutant | file | the bug | killed by |", "|---|---|---|---|"]
    known = blind_spots()
    for row in doc["mutants"]:
        why = row.get("blind_spot") or known.get(row["id"], "")
        verdict = _killer(row) if row["killed"] else \
            f"inconclusive: {row['inconclusive']}" if row.get("inconclusive") else \
            "**survived**" + (f": {why}" if why else "")
        lines.append(f"| {row['id']} | `{row['file']}` | {_cell(row['description'])} | "
                     f"{_cell(verdict)} |")
    return "\n".join(lines)


def comparison_table(docs: dict[str, dict]) -> str:
    """Held-out sets scored by several machineries: label -> campaign."""
    ids = list(dict.fromkeys(r["id"] for d in docs.values() for r in d["mutants"]))
    lines = ["| mutant | " + " | ".join(docs) + " |", "|---|" + "---|" * len(docs)]
    for i in ids:
        cells = []
        for d in docs.values():
            row = next((r for r in d["mutants"] if r["id"] == i), None)
            cells.append("–" if row is None else "killed" if row["killed"] else
                         "inconclusive (time limit)" if row.get("inconclusive") else "**survived**")
        lines.append(f"| {i} | " + " | ".join(cells) + " |")
    lines.append("| **score** | " + " | ".join(f"{d['killed']}/{d['total']}" for d in docs.values())
                 + " |")
    return "\n".join(lines)


def cosmic_ray_table(doc: dict) -> str:
    """Per package: mutants generated, sampled, killed, survived, not settled; and the score."""
    lines = ["| package | mutants | equivalent | run | killed | survived | not settled | score |",
             "|---|---|---|---|---|---|---|---|"]
    for pkg, s in doc["packages"].items():
        judged = s["killed"] + s["survived"]
        score = f"{100 * s['killed'] / judged:.0f} %" if judged else "–"
        lines.append(f"| {pkg} | {s['mutants']} | {s.get('equivalent', 0)} | {s['sampled']} | "
                     f"{s['killed']} | "
                     f"{s['survived']} | {s['unsettled']} | {score} |")
    if doc.get("survivors"):
        lines.append("")
    for row in doc.get("survivors", []):
        lines.append(f"* survived: `{row['file']}` line {row['line']}, {row['operator']}")
    return "\n".join(lines)
