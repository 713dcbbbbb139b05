"""The claims of the seeds as data: one entry per claim, in ``suite/claims/*.toml``.

An entry (``[[claim]]``)::

    id         = "B-4.2-d"                       # as in the claims inventory
    kind       = "E"                             # E: needs a run; I: identity / structure
    citation   = "[B] §4.2, text before Fig 7"
    claim      = "Euler, h = 0.1: after 55 steps |err| > 1 for both integrals"   # our own words
    seed_value = "> 1 after 55 steps"            # what the seed says, as text
    threshold  = "seed"                          # seed: the seed states the number; proposed: we do
    expected   = "reproduced"                    # the verdict we expect (known deficiencies: other)
    figure     = "b-fig-7"                       # the figure it belongs to (a link), optional
    reading    = "..."                           # a doubtful OCR reading and the one used, optional
    note       = "..."                           # optional
    one_sided  = "..."                           # why passes reads one side only (see below)

and exactly one way of being checked:

* **measured on runs**: ``experiment = "b-claims-4.2"`` (a shipped experiment id) and
  ``values.<name> = {cells = "label=Euler h=0.1", column = "max_abs_err_H1"}`` (a column of
  ``cells.parquet``) or ``{cells = ..., sample = "err_H1", at = "steps=55"}`` (a column of
  ``samples.parquet`` at ``last``, ``steps=N``, ``t=T`` (the sample at T of a run that reached T,
  to 1e-9 relative; none: not measured), or reduced
  over the samples: ``max_abs``, ``min``, ``max``); several cells need ``reduce = "max"``
  (min, max, mean, all, any). Then ``measured = "<expression>"`` and ``passes =
  "<expression over measured and the values>"``, optionally ``partly = "<expression>"``.
  ``sweep = "problem"`` (or any column) evaluates the claim once per value of that column among
  the selected cells (the seed leaves a parameter open): all pass -> reproduced, none -> not
  reproduced, else partly.
* **a closed form** derived from the method's map or the flow: ``closed_form = "<registered>"``
  (:mod:`gnibench.suite.ledger.closed_forms`), with ``experiment``/``cells`` for the runs it is
  compared with; it adds named values (e.g. ``deviation``) for ``measured``/``passes``.
* **an identity**: ``check = "<registered>"`` (:mod:`gnibench.suite.ledger.identities`), a small
  computation (no long integration); it returns named values for ``measured``/``passes``.
* **an aggregate**: ``all_of = ["B-4.2-g", "B-4.2-h"]``: reproduced when all are (a part not in
  the ledger yet is "not checkable": :func:`missing_parts`).
* **not checkable**: ``not_checkable = "why"`` (a diagram, a photo, a result of another work, a
  method of another work in whose place we run ours); ``experiment`` with ``side.<name> = {...}``
  (as ``values``) shows our own numbers beside the verdict, as a side result.

Optional keys of every entry that reads runs: ``accept = ["step_too_small"]`` (also per value):
failure statuses that are the claimed behaviour itself (a method breaking down), so the failed
run's values are measured over what it computed; ``reach = "horizon"``: the experiment records
all section crossings up to its horizon, the point count being a cap (a run that reached its
horizon is complete); ``needed = "..."``: what would have been needed to reproduce the claim
(shown on the ledger page). Otherwise a value from a failed or truncated run, or at a time or
step the run did not reach, is not measured and the claim not reproduced
(:mod:`gnibench.suite.ledger.reach`). ``expected`` may also be ``not measured``: not reproduced
because a run it needs does not complete (a regression record, like every ``expected``).
A pass criterion that bounds a measured number on one side only (``measured >= 10``) states the
other side where the seed gives one (a value "of order 10⁻¹⁰" is read within a factor 10 both
ways); otherwise the entry says why in ``one_sided`` (a distance, >= 0 by construction; an
inequality of the seed; "bounded"; "better" without a size): :mod:`gnibench.suite.ledger.sides`
finds the one-sided comparisons, and the tests check that exactly those entries give a reason.
Cell selectors: ``field=value`` / ``field~value`` terms joined by ``&``, alternatives by ``|``.
Ids: those of the claims inventory, and ``<id>.corrected`` for the corrected relation of a seed's slip (the
printed statement keeps the inventory id).

The keys, their types, defaults and what each allows are the fields of :class:`Claim` and
:class:`Value` below (a new key is one line there; the documentation's table of claim keys is rendered
from them); the rules between keys are :meth:`Claim._one_way`. Expressions are those of
:mod:`gnibench.suite.foundation.expressions` (bounded, checked when the ledger is read).
"""
from __future__ import annotations

import math
import re
from importlib import resources
from typing import Annotated, Literal

from gnibench.suite.foundation import expressions
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.foundation.records import Allowed, Line, NonEmptyLine, Record, Text, key, validate
from gnibench.suite.foundation.tomlfile import load_toml
from pydantic import AfterValidator, Field, PrivateAttr, model_validator

VERDICTS = ("reproduced", "not reproduced", "partly", "not checkable", "not measured")
#: the failure statuses a claim may accept as its claimed behaviour (suite/foundation/status.py)
FAILURES = ("nonfinite", "newton_failed", "max_steps", "step_too_small")
REDUCE = ("min", "max", "mean", "all", "any", "sum")
_AT = re.compile(r"^(last|max_abs|min|max|[A-Za-z_][A-Za-z0-9_]*=[-+]?(\d+\.?\d*|\.\d+)"
                 r"([eE][-+]?\d{1,3})?)$")


def _expression(text: str) -> str:
    try:
        expressions.parse(text, "expression")     # bounded; refused here, before any run
    except UserError as e:
        raise ValueError(str(e).removeprefix("expression: ")) from None
    return text


def _at(text: str) -> str:
    if not _AT.match(text) or "=" in text and not math.isfinite(float(text.partition("=")[2])):
        raise ValueError(f"bad at = {text[:60]!r}; allowed: last, max_abs, min, max, steps=N, "
                         f"t=T (a column = a finite number)")
    return text


Expression = Annotated[str, Allowed("a safe expression (suite/foundation/expressions.py)"),
                       Field(max_length=expressions.MAX_CHARS), AfterValidator(_expression)]
Name = Annotated[str, Field(pattern=r"^[A-Za-z_][A-Za-z0-9_]*$", max_length=64)]


class Value(Record):
    """``values.<name> = {...}``: a number read from the tables of the claim's experiment."""

    cells: Line = key(doc="the cells (a selector: label=..., method~..., & between terms)")
    column: Line | None = key(None, "a column of cells.parquet (a per-cell metric)")
    sample: Line | None = key(None, "a column of samples.parquet")
    at: Annotated[Line, AfterValidator(_at)] | None = key(
        None, "which sample: last (default), steps=N, t=T, or reduced: max_abs, min, max")
    reduce: Literal[REDUCE] | None = key(None, "over several cells (default max)")
    accept: Annotated[list[Literal[FAILURES]], Field(max_length=4)] | None = key(
        None, "failure statuses that are the claimed behaviour: the failed run is measured over "
              "what it computed")

    @model_validator(mode="after")
    def _one_column(self):
        if (self.column is None) == (self.sample is None):
            raise ValueError("give exactly one of column (cells.parquet) or sample "
                             "(samples.parquet)")
        return self


def _plain(value: Value) -> dict:
    return value.model_dump(exclude_none=True)


class Claim(Record):
    """One ledger entry (``[[claim]]``; see the module docstring)."""

    id: Annotated[str, Field(pattern=r"^(B|HLW)-[A-Za-z0-9.\-]+$", max_length=80)] = key(
        doc="as in the claims inventory", allowed="B-... or HLW-... as in the claims inventory")
    kind: Literal["E", "I"] = key(doc="E: needs a run; I: an identity or structure")
    citation: NonEmptyLine = key(doc="the place in the seed")
    claim: NonEmptyLine = key(doc="the claim in our own words")
    seed_value: Line = key("", "what the seed says, as text")
    threshold: Literal["seed", "proposed", "closed form", "none"] = key(
        "proposed", "whose number the pass criterion uses")
    expected: Literal[VERDICTS] = key("reproduced", "the verdict we expect (known deficiencies: "
                                                    "another)")
    figure: Line = key("", "the figure it belongs to (a link)")
    reading: Text = key("", "a doubtful OCR reading and the one used")
    note: Text = key("", "a note")
    experiment: Line = key("", "the shipped experiment whose runs it reads")
    values: Annotated[dict[Name, Annotated[Value, AfterValidator(_plain)]],
                      Field(max_length=64)] = key({}, "named numbers read from the tables",
                                                  "a table name = {cells, column | sample, at, "
                                                  "reduce}")
    measured: Expression = key("", "the measured number: an expression over the values")
    passes: Expression = key("", "the pass criterion: an expression over measured and the values")
    partly: Expression = key("", "a weaker criterion (verdict partly)")
    sweep: Line = key("", "judge once per value of this column of the selected cells")
    closed_form: Line = key("", "a registered closed form (suite/ledger/closed_forms.py)")
    cells: Line = key("", "the cells a closed form is compared with")
    check: Line = key("", "a registered identity (suite/ledger/identities.py)")
    all_of: Annotated[list[NonEmptyLine], Field(max_length=200), AfterValidator(tuple)] = key(
        (), "an aggregate: reproduced when all these claims are", "a list of claim ids")
    not_checkable: Text = key("", "why it cannot be checked")
    scale: Literal["", "paper"] = key("", "paper: skipped at the quick scale", "paper")
    accept: Annotated[list[Literal[FAILURES]], Field(max_length=4), AfterValidator(tuple)] = key(
        (), "failure statuses that are the claimed behaviour (all the entry's cells)")
    reach: Literal["", "horizon"] = key(
        "", "horizon: a section run that reached its horizon is complete (the count is a cap)")
    needed: Text = key("", "what would have been needed to reproduce the claim")
    one_sided: Text = key("", "why passes bounds a measured number on one side only (the seed gives "
                              "no other side; suite/ledger/sides.py)")
    side: Annotated[dict[Name, Annotated[Value, AfterValidator(_plain)]],
                    Field(max_length=64)] = key({}, "a not-checkable entry's side result: our "
                                                    "numbers, read as values are, shown beside it",
                                                "a table name = {cells, column | sample, at, "
                                                "reduce}")
    _source: str = PrivateAttr("")

    @property
    def source(self) -> str:
        """The file the entry comes from."""
        return self._source

    @property
    def how(self) -> str:
        for name in ("check", "closed_form", "all_of", "not_checkable"):
            if getattr(self, name):
                return name
        return "measured"

    @model_validator(mode="after")
    def _one_way(self):
        given = self.model_fields_set
        ways = [k for k in ("check", "closed_form", "all_of", "not_checkable") if k in given]
        if "values" in given or ("passes" in given and not ways):
            ways.append("measured")
        if len(ways) != 1:
            raise ValueError(f"give exactly one of values (+ measured, passes), check, "
                             f"closed_form, all_of, not_checkable; got {ways or 'none'}")
        how = ways[0]
        if how in ("measured", "closed_form") and not self.experiment:
            raise ValueError("needs experiment = <shipped experiment id>")
        if how in ("measured", "check", "closed_form") and "passes" not in given:
            raise ValueError("needs passes = <expression>")
        if how == "measured":
            if "measured" not in given:
                raise ValueError("needs measured = <expression over the values>")
            missing = expressions.parse(self.measured, "measured").names - set(self.values)
            if missing:
                raise ValueError(f"measured uses unknown names {sorted(missing)}")
        return self


def shipped_files() -> dict[str, str]:
    root = resources.files("gnibench.suite") / "claims"
    return {f.name: f.read_text(encoding="utf-8") for f in root.iterdir()
            if f.name.endswith(".toml")}


def load_ledger() -> dict[str, Claim]:
    """Every claim of the shipped ledger, by id, validated."""
    claims: dict[str, Claim] = {}
    for name, text in sorted(shipped_files().items()):
        for claim in parse_claims(text, name):
            if claim.id in claims:
                raise UserError(f"{name}: claim {claim.id} is also in {claims[claim.id].source}")
            claims[claim.id] = claim
    return claims


def missing_parts(ledger: dict[str, Claim]) -> dict[str, list[str]]:
    """Parts of aggregates that are not in the ledger, by aggregate id. An aggregate may name the
    claims of a section whose entries are still being written (the claims inventory ids); verify judges the
    missing parts "not checkable" and says so, and the tests list the ones still expected."""
    return {c.id: [p for p in c.all_of if p not in ledger]
            for c in ledger.values() if any(p not in ledger for p in c.all_of)}


def parse_claims(text: str, source: str) -> list[Claim]:
    doc = load_toml(text, source)
    if set(doc) - {"claim"}:
        raise UserError(f"{source}: unknown top-level keys {sorted(set(doc) - {'claim'})}; "
                        f"allowed: [[claim]] entries")
    entries = doc.get("claim", [])
    if not isinstance(entries, list):
        raise UserError(f"{source}: bad claim; allowed: [[claim]] entries")
    claims = []
    for entry in entries:
        ident = entry.get("id", "?") if isinstance(entry, dict) else "?"
        claim = validate(Claim, entry, f"{source}: claim {str(ident)[:80]}")
        claim._source = source
        claims.append(claim)
    return claims
