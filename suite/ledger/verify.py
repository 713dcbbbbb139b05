"""``gnibench verify``: choose claims, run what they need, judge them, write the ledger table.

The runs go through the runner with one shared store (:func:`gnibench.suite.runs.runner.
run_experiments`), so they are parallel and resumable and shared with ``gnibench reproduce``
when both use the same store. The verdicts are judged from the tables only
(:mod:`gnibench.suite.ledger.verdicts`) and written as ``ledger.parquet`` (one row per claim; the
provenance of the runs is in the experiments' own tables).
"""
from __future__ import annotations

from pathlib import Path

import pandas as pd
from gnibench.suite.foundation.errors import UserError, unknown
from gnibench.suite.ledger.entries import Claim, load_ledger
from gnibench.suite.ledger.verdicts import Results, Verdict, evaluate


def select_claims(ids: list[str]) -> list[Claim]:
    """The claims named (``all`` or nothing: every claim), with the parts of aggregates."""
    ledger = load_ledger()
    if not ids or ids == ["all"]:
        chosen = list(ledger)
    else:
        chosen = []
        for i in ids:
            if i not in ledger:
                raise unknown("claim", i, ledger)
            chosen.append(i)
    todo, seen = list(chosen), set()
    while todo:                                     # the parts of aggregates are judged too
        i = todo.pop()
        if i in seen:
            continue
        seen.add(i)
        todo.extend(p for p in ledger[i].all_of if p in ledger)   # missing: not checkable
    return [c for c in ledger.values() if c.id in seen]


def needed_experiments(claims: list[Claim], scale: str) -> list[str]:
    out: list[str] = []
    for c in claims:
        if c.experiment and c.experiment not in out and not (c.scale == "paper"
                                                             and scale != "paper"):
            out.append(c.experiment)
    return out


def judge(claims: list[Claim], results: Results, scale: str) -> list[Verdict]:
    """Verdicts in ledger order; aggregates after their parts."""
    done: dict[str, Verdict] = {}
    pending = list(claims)
    known = set(load_ledger())
    while pending:
        rest = []
        for c in pending:
            if all(p in done or p not in known for p in c.all_of):
                done[c.id] = evaluate(c, results, done, scale)
                missing = [p for p in c.all_of if p not in known]
                if missing:
                    done[c.id].detail = (f"not in the ledger: {', '.join(missing)}"
                                         + (f"; {done[c.id].detail}" if done[c.id].detail else ""))
            else:
                rest.append(c)
        if len(rest) == len(pending):
            raise UserError(f"aggregate claims form a cycle: {[c.id for c in rest]}")
        pending = rest
    return [done[c.id] for c in claims]


def ledger_table(verdicts: list[Verdict]) -> pd.DataFrame:
    return pd.DataFrame([v.row() for v in verdicts])


def write_ledger(verdicts: list[Verdict], out: Path, meta: dict) -> Path:
    from gnibench.suite.runs.storage import write_parquet

    out.mkdir(parents=True, exist_ok=True)
    path = out / "ledger.parquet"
    write_parquet(ledger_table(verdicts), path, {"table": "ledger", **meta})
    return path
