"""Verdicts: each claim of the ledger checked against the tables of the runs (never integrating,
except the cheap identity checks), with the measured number beside the seed's.

A verdict is one of

* ``reproduced`` (the pass criterion holds), ``partly`` (a weaker criterion holds, or the verdict
  differs across a sweep of a parameter the seed leaves open), ``not reproduced`` (it does not,
  with the numbers; also when a value it needs was *not measured*: a failed or truncated run, a
  time the run did not reach — :mod:`.reach` — and then the detail says where the run stopped);
* ``not checkable``: only for entries that are not computations (``not_checkable = "why"``: a
  diagram, a result of another work, a method swap);
* ``skipped``: a claim meaningful at the paper scale only, at the quick scale;
* ``error``: the measurement itself failed (a column or cell that does not exist, a closed form
  that raised, an expression naming a value nobody gave). Always unexpected: exit 1.

``expected`` is a regression record of our own outcome, not evidence: a verdict differs from it
when the code or the runs changed. A claim that was not reproduced because a value was not
measured has the outcome ``not measured`` for this comparison (so a run that starts to fail is
noticed even where the claim was not reproduced before).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
from gnibench.suite.foundation import expressions
from gnibench.suite.ledger import closed_forms, identities, misses
from gnibench.suite.ledger.entries import Claim
from gnibench.suite.ledger.reach import NotMeasured, Run, at_sample, require_complete, runs_of
from gnibench.suite.runs.storage import read_parquet

SKIPPED, ERROR, NOT_MEASURED = "skipped", "error", "not measured"
#: a closed form with more named values than this (the §6 statistics of several cells give 100+)
#: is summarised in ``detail`` (ledger.md, the ledger page) by the values its verdict reads: those
#: of its measured, passes and partly expressions; ``values`` (ledger.parquet) keeps them all
SHOWN_VALUES = 12
VERDICT_ORDER = ("reproduced", "partly", "not reproduced", "not checkable", SKIPPED, ERROR)


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
    values: str = ""                                  # every named value (ledger.parquet only)
    reading: str = ""
    experiment: str = ""
    sweep: list = field(default_factory=list)
    runs: list = field(default_factory=list)          # Run records of the cells it read
    not_measured: str = ""                            # why a value could not be measured
    failing: str = ""                                 # the conjuncts of passes that fail
    closest: str = ""                                 # the sweep point that came closest
    needed: str = ""                                  # the entry's words: what would be needed
    miss_items: list = field(default_factory=list)    # (failing conjunct, factor off)
    horizon_only: bool = False                        # the entry's reach = "horizon"
    parts: list = field(default_factory=list)         # an aggregate's part verdicts

    @property
    def runs_complete(self) -> bool:
        """Every run it read complete by its entry's rule (a section run that reached its horizon
        is complete under reach = "horizon"; an accepted failure is not complete)."""
        if self.parts:
            return all(p.runs_complete for p in self.parts)
        return all(r.complete(self.horizon_only) for r in self.runs)

    @property
    def outcome(self) -> str:
        """The verdict compared with ``expected``: ``not measured`` for a claim not reproduced
        because a value it needs was not measured."""
        return NOT_MEASURED if self.verdict == "not reproduced" and self.not_measured \
            else self.verdict

    @property
    def unexpected(self) -> bool:
        if self.verdict == ERROR:
            return True
        if self.verdict == SKIPPED:
            return False
        return self.outcome != self.expected

    def row(self) -> dict:
        measured = self.measured
        number = float(measured) if isinstance(measured, (int, float, np.floating)) else np.nan
        return {"id": self.id, "citation": self.citation, "claim": self.claim,
                "verdict": self.verdict, "expected": self.expected, "outcome": self.outcome,
                "unexpected": self.unexpected, "measured": number,
                "measured_text": _text(measured), "seed_value": self.seed_value,
                "threshold": self.threshold, "figure": self.figure, "experiment": self.experiment,
                "reading": self.reading, "detail": self.detail, "values": self.values,
                "sweep": "; ".join(f"{k}: {v}" for k, v in self.sweep),
                "runs": "\n".join(dict.fromkeys(r.describe() for r in self.runs)),
                "runs_complete": self.runs_complete,
                "not_measured": self.not_measured, "failing": self.failing,
                "closest": self.closest, "needed": self.needed}


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
            self._tables[experiment] = (read_parquet(d / "cells.parquet"),
                                        read_parquet(d / "samples.parquet"))
        return self._tables[experiment]


def select(cells: pd.DataFrame, text: str) -> pd.DataFrame:
    """Cells matching ``field=value`` (equal) or ``field~value`` (contains) terms joined by ``&``,
    alternatives joined by ``|`` (``label=a | label=b``); fields: label, group, cell, problem,
    method, status. An empty selector selects all."""
    if "|" in text:
        mask = np.zeros(len(cells), dtype=bool)
        for alternative in text.split("|"):
            mask |= cells.index.isin(select(cells, alternative).index)
        return cells[mask]
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


class _Reader:
    """Reads a claim's values from one experiment's tables, keeping the runs it used."""

    def __init__(self, claim: Claim, cells: pd.DataFrame, samples: pd.DataFrame):
        self.claim, self.cells, self.samples = claim, cells, samples
        self.runs: list[Run] = []

    def chosen(self, text: str, restrict=None) -> pd.DataFrame:
        chosen = select(self.cells, text)
        if restrict is not None:
            chosen = chosen[chosen[restrict[0]].astype(str) == restrict[1]]
        if chosen.empty:
            raise LookupError(f"no cell matches {text!r}")
        return chosen

    def runs_checked(self, chosen: pd.DataFrame, accept=()) -> list[Run]:
        runs = runs_of(self.claim.experiment, chosen)
        self.runs.extend(runs)
        require_complete(runs, tuple(accept) + tuple(self.claim.accept),
                         horizon_only=self.claim.reach == "horizon")
        return runs

    def names_exist(self, spec: dict) -> None:
        """KeyError for a column the tables do not have, checked before the runs' status: a
        typo is an error even where the run it names did not complete."""
        if "column" in spec and spec["column"] not in self.cells.columns:
            raise KeyError(f"no column {spec['column']!r} in cells.parquet")
        if "sample" in spec and spec["sample"] not in self.samples.columns:
            raise KeyError(f"no column {spec['sample']!r} in samples.parquet")
        key = spec.get("at", "last").partition("=")[0]
        if "=" in spec.get("at", "") and key not in self.samples.columns:
            raise KeyError(f"no sample column {key!r} to read at {spec['at']!r}")

    def value(self, spec: dict, restrict=None) -> float:
        chosen = self.chosen(spec["cells"], restrict)
        self.names_exist(spec)
        runs = self.runs_checked(chosen, spec.get("accept", ()))
        if "column" in spec:
            vals = pd.to_numeric(chosen[spec["column"]], errors="coerce").to_numpy(dtype=float)
        else:
            vals = []
            for run in runs:
                rows = self.samples[self.samples["cell"] == run.cell]
                vals.append(at_sample(rows[spec["sample"]].to_numpy(dtype=float), rows,
                                      spec.get("at", "last"), run))
            vals = np.array(vals)
        if len(vals) > 1 and "reduce" not in spec:
            raise LookupError(f"{spec['cells']!r} selects {len(vals)} cells; give reduce = ...")
        how = spec.get("reduce", "max")
        return float({"min": np.min, "max": np.max, "mean": np.mean, "sum": np.sum,
                      "all": lambda v: float(np.all(v != 0)),
                      "any": lambda v: float(np.any(v != 0))}[how](vals))

    def closed_form(self, restrict=None) -> dict:
        chosen = self.chosen(self.claim.cells, restrict)
        closed_forms.check_name(self.claim.closed_form)     # a typo before the runs' status
        self.runs_checked(chosen)
        return closed_forms.run(self.claim.closed_form, chosen, self.samples)

    def values(self, restrict=None) -> dict:
        if self.claim.how == "closed_form":
            return self.closed_form(restrict)
        return {k: self.value(s, restrict) for k, s in self.claim.values.items()}


def evaluate(claim: Claim, results: Results, done: dict[str, Verdict],
             scale: str = "paper") -> Verdict:
    """The verdict of one claim (aggregates need the verdicts of their parts in ``done``).
    Anything that goes wrong while measuring is the verdict ``error``, with the exception."""
    v = Verdict(claim.id, claim.citation, claim.claim, "not checkable", claim.expected, None,
                claim.seed_value, claim.threshold, claim.figure, reading=claim.reading,
                experiment=claim.experiment, needed=claim.needed,
                horizon_only=claim.reach == "horizon")
    try:
        return _evaluate(v, claim, results, done, scale)
    except Exception as e:                     # noqa: BLE001 - a broken entry is a verdict
        v.verdict, v.measured = ERROR, None
        v.detail = f"the measurement failed: {type(e).__name__}: {e}"
        return v


def _evaluate(v: Verdict, claim: Claim, results: Results, done: dict, scale: str) -> Verdict:
    how = claim.how
    if how == "not_checkable":
        v.detail = claim.not_checkable
        if claim.side and not (claim.scale == "paper" and scale != "paper"):
            _side(v, claim, results)
        return v
    if how == "all_of":
        return _aggregate(v, claim, done)
    if claim.scale == "paper" and scale != "paper":
        v.verdict = SKIPPED
        v.detail = "meaningful at the paper scale only (gnibench verify --scale paper)"
        return v
    if how == "check":
        return _judge(v, claim, identities.run(claim.check))
    tables = results.tables(claim.experiment)
    if tables is None:
        raise LookupError(f"experiment {claim.experiment} has no results here")
    reader = _Reader(claim, *tables)
    if how == "measured":
        _names_given(claim)
        for spec in claim.values.values():
            reader.names_exist(spec)
    if claim.sweep:
        return _sweep(v, claim, reader)
    try:
        values = reader.values()
    except NotMeasured as e:
        v.runs = reader.runs
        return _not_measured(v, str(e))
    v.runs = reader.runs
    return _judge(v, claim, values)


def _names_given(claim: Claim) -> None:
    """NameError for a name of passes or partly that no value gives, checked before any value is
    read (a run that did not complete would otherwise hide the typo behind "not measured")."""
    known = set(claim.values) | {"measured"}
    for key in ("passes", "partly"):
        text = getattr(claim, key)
        unknown = expressions.parse(text, claim.id).names - known if text else set()
        if unknown:
            raise NameError(f"{key} uses {', '.join(sorted(unknown))}, which no value gives "
                            f"(values: {', '.join(sorted(known))})")


def _side(v: Verdict, claim: Claim, results: Results) -> None:
    """Our own numbers beside a not-checkable verdict (a method swap's side result)."""
    tables = results.tables(claim.experiment)
    if tables is None:
        raise LookupError(f"experiment {claim.experiment} has no results here")
    reader = _Reader(claim, *tables)
    try:
        side = {k: reader.value(s) for k, s in claim.side.items()}
        v.measured = "side result: " + ", ".join(f"{k} = {_text(x)}" for k, x in side.items())
    except NotMeasured as e:
        v.detail += f"; side result not measured: {e}"
    v.runs = reader.runs


def _not_measured(v: Verdict, why: str) -> Verdict:
    v.verdict, v.measured, v.not_measured = "not reproduced", None, why
    v.detail = f"not measured: {why}"
    return v


def _aggregate(v: Verdict, claim: Claim, done: dict) -> Verdict:
    parts = [done.get(i) for i in claim.all_of]
    got = [p.verdict if p else "not checkable" for p in parts]
    v.measured = ", ".join(f"{i}: {g}" for i, g in zip(claim.all_of, got))
    if ERROR in got:
        v.verdict = ERROR
        v.detail = "a part could not be measured (error)"
        return v
    judged = [g for g in got if g not in ("not checkable", SKIPPED)]
    if not judged:
        v.verdict = SKIPPED if SKIPPED in got else "not checkable"
        v.detail = "none of its parts could be judged here"
    elif all(g == "reproduced" for g in judged):
        v.verdict = "reproduced" if len(judged) == len(got) else "partly"
    elif any(g in ("reproduced", "partly") for g in judged):
        v.verdict = "partly"
    else:
        v.verdict = "not reproduced"
    for p in parts:
        if p is not None:
            v.runs.extend(p.runs)
            v.parts.append(p)
    if v.verdict != "reproduced":
        off = [f"{i}: {g}" for i, g in zip(claim.all_of, got) if g != "reproduced"]
        v.failing = "; ".join(off)
    return v


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
    if v.verdict != "reproduced":
        v.miss_items = misses.failing(claim.passes, values, claim.id)
        v.failing = misses.describe(v.miss_items)
    named = {k: x for k, x in values.items() if k != "measured"}
    v.values = ", ".join(f"{k} = {_text(x)}" for k, x in named.items())
    v.detail = detail or summary(claim, named)
    return v


def summary(claim: Claim, named: dict) -> str:
    """``k = v, ...`` of the named values, or, when there are more than ``SHOWN_VALUES``, of those
    the verdict reads (the names of measured, passes and partly) and how many more there are."""
    if len(named) <= SHOWN_VALUES:
        return ", ".join(f"{k} = {_text(x)}" for k, x in named.items())
    read = set().union(*(expressions.parse(text, claim.id).names
                         for text in (claim.measured, claim.passes, claim.partly) if text))
    shown = [k for k in named if k in read]
    return (", ".join(f"{k} = {_text(named[k])}" for k in shown)
            + f"{'; ' if shown else ''}{len(named) - len(shown)} more values in ledger.parquet "
              "(column values)")


def _sweep(v: Verdict, claim: Claim, reader: _Reader) -> Verdict:
    points, ranked, unmeasured, swept = [], [], [], []
    if claim.how == "closed_form":
        chosen = reader.chosen(claim.cells)
    else:
        chosen = pd.concat([reader.chosen(s["cells"]) for s in claim.values.values()])
    for key in pd.unique(chosen[claim.sweep].astype(str)):     # among the selected cells
        point = Verdict(claim.id, "", "", "", "", None, "", "")
        try:
            values = reader.values((claim.sweep, key))
        except NotMeasured as e:
            _not_measured(point, str(e))
            points.append((key, "not measured"))
            unmeasured.append(f"{claim.sweep} {key}: {e}")
        else:
            _judge(point, claim, values)
            swept.append(f"{claim.sweep} {key}: {point.values}")
            if point.verdict != "reproduced":   # closest among the points that fail
                ranked.append((misses.closeness(point.miss_items), key, point))
            points.append((key, f"{point.verdict} ({_text(point.measured)})"))
        v.sweep.append((key, point.verdict))
    v.runs = reader.runs
    v.values = "; ".join(swept)
    verdicts = [s for _, s in v.sweep]
    v.verdict = ("reproduced" if all(s == "reproduced" for s in verdicts) else
                 "not reproduced" if all(s == "not reproduced" for s in verdicts) else "partly")
    v.measured = "; ".join(f"{k}: {m}" for k, m in points)
    v.detail = f"over {claim.sweep}: the seed leaves it open"
    if unmeasured and len(unmeasured) == len(points):    # nothing measured at all
        v.not_measured = "; ".join(unmeasured)
        v.detail = f"not measured: {v.not_measured}"
    elif unmeasured:
        v.detail += "; not measured at " + "; ".join(unmeasured)
    if ranked and v.verdict != "reproduced":
        ranked.sort(key=lambda r: r[0])
        _, key, best = ranked[0]
        v.closest = f"{claim.sweep} {key}: {best.verdict} ({_text(best.measured)})" + (
            f"; {best.failing}" if best.failing else "")
        v.failing = best.failing
    return v
