"""Verdicts: each claim of the ledger checked against the tables of the runs (never integrating,
except the cheap identity checks) — reproduced, not reproduced, partly, or not checkable — with the
measured number beside the seed's."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
from gnibench.suite.foundation import expressions
from gnibench.suite.ledger import closed_forms, identities
from gnibench.suite.ledger.entries import Claim


@dataclass
class Verdict:
    """The outcome of one claim."""

    id: str
    citation: str
    claim: str
    verdict: str
    expected: str
    measured: object
    seed_value: str
    threshold: str
    figure: str = ""
    detail: str = ""
    reading: str = ""
    experiment: str = ""
    sweep: list = field(default_factory=list)

    @property
    def unexpected(self) -> bool:
        return self.verdict != self.expected and self.verdict != "not checkable"

    def row(self) -> dict:
        measured = self.measured
        number = float(measured) if isinstance(measured, (int, float, np.floating)) else np.nan
        return {"id": self.id, "citation": self.citation, "claim": self.claim,
                "verdict": self.verdict, "expected": self.expected,
                "unexpected": self.unexpected, "measured": number,
                "measured_text": _text(measured), "seed_value": self.seed_value,
                "threshold": self.threshold, "figure": self.figure, "experiment": self.experiment,
                "reading": self.reading, "detail": self.detail,
                "sweep": "; ".join(f"{k}: {v}" for k, v in self.sweep)}


def _text(x) -> str:
    if isinstance(x, (float, np.floating)):
        return f"{x:.4g}"
    return "" if x is None else str(x)


class Results:
    """The tables of the experiments' results directories, read once."""

    def __init__(self, dirs: dict[str, Path]):
        self.dirs = {k: Path(v) for k, v in dirs.items()}
        self._tables: dict[str, tuple] = {}

    def tables(self, experiment: str):
        if experiment not in self._tables:
            d = self.dirs.get(experiment)
            if d is None or not (d / "cells.parquet").is_file():
                return None
            self._tables[experiment] = (pd.read_parquet(d / "cells.parquet"),
                                        pd.read_parquet(d / "samples.parquet"))
        return self._tables[experiment]


def select(cells: pd.DataFrame, text: str) -> pd.DataFrame:
    """Cells matching ``field=value`` (equal) or ``field~value`` (contains) terms joined by ``&``;
    fields: label, group, cell, problem, method, status. An empty selector selects all."""
    mask = np.ones(len(cells), dtype=bool)
    for term in filter(None, (t.strip() for t in text.split("&"))):
        op = "~" if "~" in term and ("=" not in term or term.index("~") < term.index("=")) else "="
        name, _, value = term.partition(op)
        name, value = name.strip(), value.strip()
        if name not in cells.columns:
            raise KeyError(f"no column {name!r} to select cells on")
        col = cells[name].astype(str)
        mask &= col.str.contains(value, regex=False).to_numpy() if op == "~" else \
            (col == value).to_numpy()
    return cells[mask]


def _value(spec: dict, cells: pd.DataFrame, samples: pd.DataFrame, restrict=None) -> float:
    chosen = select(cells, spec["cells"])
    if restrict is not None:
        chosen = chosen[chosen[restrict[0]].astype(str) == restrict[1]]
    if chosen.empty:
        raise LookupError(f"no cell matches {spec['cells']!r}")
    if "column" in spec:
        vals = pd.to_numeric(chosen[spec["column"]], errors="coerce").to_numpy(dtype=float)
    else:
        vals = np.array([_at(samples[samples["cell"] == c][spec["sample"]].to_numpy(dtype=float),
                             samples[samples["cell"] == c], spec.get("at", "last"))
                         for c in chosen["cell"]])
    if len(vals) > 1 and "reduce" not in spec:
        raise LookupError(f"{spec['cells']!r} selects {len(vals)} cells; give reduce = ...")
    how = spec.get("reduce", "max")
    return float({"min": np.min, "max": np.max, "mean": np.mean, "sum": np.sum,
                  "all": lambda v: float(np.all(v != 0)),
                  "any": lambda v: float(np.any(v != 0))}[how](vals))


def _at(column: np.ndarray, rows: pd.DataFrame, at: str) -> float:
    if len(column) == 0:
        return math.nan
    if at == "last":
        return float(column[-1])
    if at in ("max_abs", "min", "max"):
        a = np.abs(column) if at == "max_abs" else column
        a = np.where(np.isnan(a), np.inf, a) if at != "min" else a
        return float(np.max(a) if at != "min" else np.min(a))
    key, _, number = at.partition("=")
    target = float(number)
    where = rows[key].to_numpy(dtype=float)
    idx = np.nonzero(where <= target * (1 + 1e-12))[0]
    return float(column[idx[-1]]) if len(idx) else math.nan


def evaluate(claim: Claim, results: Results, done: dict[str, Verdict],
             scale: str = "paper") -> Verdict:
    """The verdict of one claim (aggregates need the verdicts of their parts in ``done``)."""
    v = Verdict(claim.id, claim.citation, claim.claim, "not checkable", claim.expected, None,
                claim.seed_value, claim.threshold, claim.figure, reading=claim.reading,
                experiment=claim.experiment)
    how = claim.how
    if how == "not_checkable":
        v.detail = claim.not_checkable
        return v
    if how == "all_of":
        parts = [done.get(i) for i in claim.all_of]
        got = [p.verdict if p else "not checkable" for p in parts]
        v.measured = ", ".join(f"{i}: {g}" for i, g in zip(claim.all_of, got))
        checkable = [g for g in got if g != "not checkable"]
        if not checkable:
            v.detail = "none of its parts could be checked"
        elif all(g == "reproduced" for g in checkable):
            v.verdict = "reproduced" if len(checkable) == len(got) else "partly"
        elif any(g in ("reproduced", "partly") for g in checkable):
            v.verdict = "partly"
        else:
            v.verdict = "not reproduced"
        return v
    if claim.scale == "paper" and scale != "paper":
        v.detail = "meaningful at the paper scale only (gnibench verify --scale paper)"
        return v
    if how == "check":
        return _judge(v, claim, identities.run(claim.check))
    tables = results.tables(claim.experiment)
    if tables is None:
        v.detail = f"experiment {claim.experiment} has no results here"
        return v
    cells, samples = tables
    try:
        if how == "closed_form":
            return _judge(v, claim, closed_forms.run(claim.closed_form, select(cells, claim.cells),
                                                     samples))
        if claim.sweep:
            return _sweep(v, claim, cells, samples)
        values = {k: _value(s, cells, samples) for k, s in claim.values.items()}
    except (LookupError, KeyError, ValueError) as e:
        v.detail = f"cannot measure: {e}"
        return v
    return _judge(v, claim, values)


def _judge(v: Verdict, claim: Claim, values: dict) -> Verdict:
    values = dict(values)
    detail = values.pop("_detail", "")
    if claim.measured:
        values["measured"] = expressions.evaluate(expressions.parse(claim.measured, claim.id),
                                                  values)
    v.measured = values.get("measured")
    if expressions.evaluate(expressions.parse(claim.passes, claim.id), values):
        v.verdict = "reproduced"
    elif claim.partly and expressions.evaluate(expressions.parse(claim.partly, claim.id), values):
        v.verdict = "partly"
    else:
        v.verdict = "not reproduced"
    v.detail = detail or ", ".join(f"{k} = {_text(x)}" for k, x in values.items()
                                   if k != "measured")
    return v


def _sweep(v: Verdict, claim: Claim, cells, samples) -> Verdict:
    points = []
    chosen = pd.concat([select(cells, s["cells"]) for s in claim.values.values()])
    for key in pd.unique(chosen[claim.sweep].astype(str)):     # among the selected cells
        values = {k: _value(s, cells, samples, (claim.sweep, key)) for k, s in claim.values.items()}
        point = _judge(Verdict(claim.id, "", "", "", "", None, "", ""), claim, values)
        points.append((key, f"{point.verdict} ({_text(point.measured)})"))
        v.sweep.append((key, point.verdict))
    verdicts = [s for _, s in v.sweep]
    v.verdict = ("reproduced" if all(s == "reproduced" for s in verdicts) else
                 "not reproduced" if all(s == "not reproduced" for s in verdicts) else "partly")
    v.measured = "; ".join(f"{k}: {m}" for k, m in points)
    v.detail = f"over {claim.sweep}: the seed leaves it open"
    return v
