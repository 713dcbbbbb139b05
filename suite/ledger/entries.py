"""The claims of the seeds as data: one entry per claim, in ``suite/claims/*.toml``.

An entry (``[[claim]]``)::

    id         = "B-4.2-d"                       # as in CLAIMS.md
    kind       = "E"                             # E: needs a run; I: identity / structure
    citation   = "[B] §4.2, text before Fig 7"
    claim      = "Euler, h = 0.1: after 55 steps |err| > 1 for both integrals"   # our own words
    seed_value = "> 1 after 55 steps"            # what the seed says, as text
    threshold  = "seed"                          # seed: the seed states the number; proposed: we do
    expected   = "reproduced"                    # the verdict we expect (known deficiencies: other)
    figure     = "b-fig-7"                       # the figure it belongs to (a link), optional
    reading    = "..."                           # a doubtful OCR reading and the one used, optional
    note       = "..."                           # optional

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
Cell selectors: ``field=value`` / ``field~value`` terms joined by ``&``, alternatives by ``|``.
Ids: those of CLAIMS.md, and ``<id>.corrected`` for the corrected relation of a seed's slip (the
printed statement keeps the inventory id).

Expressions are those of :mod:`gnibench.suite.ledger.expressions`.
"""
from __future__ import annotations

import re
import tomllib
from dataclasses import dataclass, field
from importlib import resources

from gnibench.suite.foundation.errors import UserError
from gnibench.suite.ledger import expressions

VERDICTS = ("reproduced", "not reproduced", "partly", "not checkable", "not measured")
KEYS = ("id", "kind", "citation", "claim", "seed_value", "threshold", "expected", "figure",
        "reading", "note", "experiment", "values", "measured", "passes", "partly", "sweep",
        "closed_form", "cells", "check", "all_of", "not_checkable", "scale", "accept", "reach",
        "needed", "side")
VALUE_KEYS = ("cells", "column", "sample", "at", "reduce", "accept")
REDUCE = ("min", "max", "mean", "all", "any", "sum")
_ID = re.compile(r"^(B|HLW)-[A-Za-z0-9.\-]+$")


@dataclass(frozen=True)
class Claim:
    """One validated ledger entry (see the module docstring)."""

    id: str
    kind: str
    citation: str
    claim: str
    seed_value: str
    threshold: str
    expected: str
    source: str
    figure: str = ""
    reading: str = ""
    note: str = ""
    experiment: str = ""
    values: dict = field(default_factory=dict)
    measured: str = ""
    passes: str = ""
    partly: str = ""
    sweep: str = ""
    closed_form: str = ""
    cells: str = ""
    check: str = ""
    all_of: tuple[str, ...] = ()
    not_checkable: str = ""
    scale: str = ""                      # "paper": skipped at the quick scale
    accept: tuple[str, ...] = ()         # failure statuses that are the claimed behaviour itself
    reach: str = ""                      # "horizon": a section run's point count is only a cap
    needed: str = ""                     # what would have been needed to reproduce it (words)
    side: dict = field(default_factory=dict)   # values shown beside a not-checkable verdict

    @property
    def how(self) -> str:
        for name in ("check", "closed_form", "all_of", "not_checkable"):
            if getattr(self, name):
                return name
        return "measured"


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
    claims of a section whose entries are still being written (CLAIMS.md ids); verify judges the
    missing parts "not checkable" and says so, and the tests list the ones still expected."""
    return {c.id: [p for p in c.all_of if p not in ledger]
            for c in ledger.values() if any(p not in ledger for p in c.all_of)}


def parse_claims(text: str, source: str) -> list[Claim]:
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise UserError(f"{source}: not valid TOML: {e}") from None
    if set(doc) - {"claim"}:
        raise UserError(f"{source}: unknown top-level keys {sorted(set(doc) - {'claim'})}; "
                        f"allowed: [[claim]] entries")
    return [_claim(entry, source) for entry in doc.get("claim", [])]


def _claim(entry: dict, source: str) -> Claim:
    where = f"{source}: claim {entry.get('id', '?')}"
    unknown = set(entry) - set(KEYS)
    if unknown:
        raise UserError(f"{where}: unknown keys {sorted(unknown)}; allowed: {', '.join(KEYS)}")
    for key in ("id", "kind", "citation", "claim"):
        if not isinstance(entry.get(key), str) or not entry[key].strip():
            raise UserError(f"{where}: missing {key} (a non-empty string)")
    if not _ID.match(entry["id"]):
        raise UserError(f"{where}: bad id; allowed: B-... or HLW-... as in CLAIMS.md")
    if entry["kind"] not in ("E", "I"):
        raise UserError(f"{where}: bad kind {entry['kind']!r}; allowed: E, I")
    expected = entry.get("expected", "reproduced")
    if expected not in VERDICTS:
        raise UserError(f"{where}: bad expected {expected!r}; allowed: {', '.join(VERDICTS)}")
    threshold = entry.get("threshold", "proposed")
    if threshold not in ("seed", "proposed", "closed form", "none"):
        raise UserError(f"{where}: bad threshold {threshold!r}; allowed: seed, proposed, "
                        f"closed form, none")
    ways = [k for k in ("check", "closed_form", "all_of", "not_checkable") if k in entry]
    if "values" in entry or ("passes" in entry and not ways):
        ways.append("measured")
    if len(ways) != 1:
        raise UserError(f"{where}: give exactly one of values (+ measured, passes), check, "
                        f"closed_form, all_of, not_checkable; got {ways or 'none'}")
    how = ways[0]
    if how in ("measured", "closed_form") and not entry.get("experiment"):
        raise UserError(f"{where}: needs experiment = <shipped experiment id>")
    if how in ("measured", "check", "closed_form"):
        if "passes" not in entry:
            raise UserError(f"{where}: needs passes = <expression>")
        known = set(entry.get("values", {})) | {"measured"}
        for key in ("measured", "passes", "partly"):
            if key in entry:
                expressions.parse(entry[key], f"{where}: {key}")
        if how == "measured":
            if "measured" not in entry:
                raise UserError(f"{where}: needs measured = <expression over the values>")
            missing = expressions.names(expressions.parse(entry["measured"], where)) - known
            if missing:
                raise UserError(f"{where}: measured uses unknown names {sorted(missing)}")
    values = {}
    for name, spec in entry.get("values", {}).items():
        values[name] = _value(spec, f"{where}: values.{name}")
    side = {name: _value(spec, f"{where}: side.{name}") for name, spec in entry.get("side", {}).items()}
    return Claim(
        id=entry["id"], kind=entry["kind"], citation=entry["citation"], claim=entry["claim"],
        seed_value=str(entry.get("seed_value", "")), threshold=threshold, expected=expected,
        source=source, figure=entry.get("figure", ""), reading=entry.get("reading", ""),
        note=entry.get("note", ""), experiment=entry.get("experiment", ""), values=values,
        measured=entry.get("measured", ""), passes=entry.get("passes", ""),
        partly=entry.get("partly", ""), sweep=entry.get("sweep", ""),
        closed_form=entry.get("closed_form", ""), cells=entry.get("cells", ""),
        check=entry.get("check", ""), all_of=tuple(entry.get("all_of", ())),
        not_checkable=entry.get("not_checkable", ""), scale=entry.get("scale", ""),
        accept=tuple(entry.get("accept", ())), reach=entry.get("reach", ""),
        needed=entry.get("needed", ""), side=side)


def _value(spec, where: str) -> dict:
    if not isinstance(spec, dict) or "cells" not in spec:
        raise UserError(f"{where}: allowed: {{cells = ..., column = ...}} or "
                        f"{{cells = ..., sample = ..., at = ...}}")
    unknown = set(spec) - set(VALUE_KEYS)
    if unknown:
        raise UserError(f"{where}: unknown keys {sorted(unknown)}; allowed: {', '.join(VALUE_KEYS)}")
    if ("column" in spec) == ("sample" in spec):
        raise UserError(f"{where}: give exactly one of column (cells.parquet) or sample "
                        f"(samples.parquet)")
    if spec.get("reduce", "max") not in REDUCE:
        raise UserError(f"{where}: bad reduce {spec['reduce']!r}; allowed: {', '.join(REDUCE)}")
    return dict(spec)
