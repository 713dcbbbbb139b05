"""Spec strings: one syntax on the CLI, in experiment files and in tables.

Grammar (public contract, see README)::

    PROBLEM  := id[:key=value,...]
    METHOD   := base[:key=value,...] { +modifier[:key=value,...] }
    lists    := a/b/c

A ``+`` starts a modifier only when a letter follows, so ``1e+6`` stays a number. Every resolved
configuration has a canonical text (:func:`canonical`) that parses back to the same configuration.
"""
from __future__ import annotations

import math
import re
import warnings
from dataclasses import dataclass

import numpy as np
from gnibench.suite.foundation.errors import UserError, unknown
from gnibench.suite.foundation.params import Bound, bind

_MODIFIER_SPLIT = re.compile(r"\+(?=[A-Za-z])")
_ID = re.compile(r"^[A-Za-z][A-Za-z0-9_-]*$")


def parse_item(text: str, what: str) -> tuple[str, dict[str, str]]:
    """Split ``id:key=value,...`` into the id and a dict of raw option texts."""
    text = text.strip()
    bad = next((c for c in text if not c.isprintable()), None)
    if bad is not None:
        raise UserError(f"bad {what} spec {text!r}: it contains {bad!r}; allowed: one line, no "
                        f"control characters")
    name, _, opts = text.partition(":")
    if not _ID.match(name):
        raise UserError(f"bad {what} spec {text!r}: expected id[:key=value,...]")
    given: dict[str, str] = {}
    if opts:
        for item in opts.split(","):
            key, eq, value = item.partition("=")
            key, value = key.strip(), value.strip()
            if not eq or not key or not value:
                raise UserError(f"bad option {item!r} in {what} spec {text!r}: expected key=value")
            if key in given:
                raise UserError(f"option {key!r} given twice in {what} spec {text!r}")
            given[key] = value
    return name, given


def split_method(text: str) -> list[str]:
    """Split a method spec into its base and modifier parts."""
    return _MODIFIER_SPLIT.split(text.strip())


@dataclass(frozen=True)
class MethodConfig:
    """A base method and its modifiers, each bound to its option values."""

    base: Bound
    modifiers: tuple[Bound, ...]

    def text(self) -> str:
        return "+".join([self.base.text()] + [m.text() for m in self.modifiers])


def parse_problem(text: str) -> Bound:
    """Resolve a PROBLEM spec against the problem registry."""
    from gnibench.problems import REGISTRY

    name, given = parse_item(text, "problem")
    if name not in REGISTRY:
        raise unknown("problem", name, REGISTRY)
    rec = REGISTRY[name]
    values = bind(rec.params, given, f"problem {name}")
    with warnings.catch_warnings(), np.errstate(all="ignore"):   # overflow is refused below
        warnings.simplefilter("ignore")
        rec.validate(values)
        check_initial_point(rec, values)
    return Bound(rec, values)


def check_initial_point(rec, values: dict) -> None:
    """Refuse an initial point where the state, a first integral or the vector field is not
    finite (an overflowing start would run as ``ok`` with every error NaN)."""
    from gnibench.problems.codegen import python_functions

    what = f"problem {rec.id}"
    try:
        y0 = tuple(float(x) for x in rec.y0(values))
    except (OverflowError, ValueError, ZeroDivisionError) as e:
        raise UserError(f"{what}: the initial point cannot be computed from these options "
                        f"({e}); allowed: options giving a finite initial point") from None
    bad = [s for s, v in zip(rec.state, y0) if not math.isfinite(v)]
    if bad:
        raise UserError(f"{what}: initial {bad[0]} = {y0[rec.state.index(bad[0])]}; allowed: "
                        f"a finite initial point")
    fns = python_functions(rec)
    par = rec.par(values)
    checks = [("the vector field", "base_f")] + [
        (f"the integral {n}", f"integral_{k}") for k, n in enumerate(_integral_names(rec))]
    for label, fn in checks:
        try:
            value = fns[fn](y0, par)
            finite = all(math.isfinite(float(v)) for v in (value if isinstance(value, tuple)
                                                           else (value,)))
        except (OverflowError, ValueError, ZeroDivisionError):
            finite = False
        if not finite:
            raise UserError(f"{what}: {label} is not finite at the initial point "
                            f"{', '.join(f'{s}={v:g}' for s, v in zip(rec.state, y0))}; "
                            f"allowed: a start where the field and the integrals are finite")


def _integral_names(rec) -> list[str]:
    from gnibench.problems.codegen import problem_meta

    return list(problem_meta(rec)["integrals"])


def parse_method(text: str, problem: Bound | None = None) -> MethodConfig:
    """Resolve a METHOD spec; with a problem, modifiers and structure needs are checked against it."""
    from gnibench.methods import ALIASES, METHODS, MODIFIERS

    parts = split_method(text)
    name, given = parse_item(parts[0], "method")
    name = ALIASES.get(name, name)
    if name not in METHODS:
        if name in MODIFIERS:
            raise UserError(f"{name!r} is a modifier, not a base method; write e.g. rk4:h=0.01+{name}")
        raise unknown("method", name, METHODS)
    rec = METHODS[name]
    values = bind(rec.params, given, f"method {name}")
    if problem is not None:          # defaults in units of the problem's time scale (h, dt_out)
        scale = problem.record.time_scale_of(problem.values)
        for p in rec.params:
            if p.scaled and p.name not in given and values.get(p.name) is not None:
                values[p.name] = p.default * scale
    base = Bound(rec, values)
    mods = []
    seen: set[str] = set()
    for part in parts[1:]:
        mname, mgiven = parse_item(part, "modifier")
        if mname not in MODIFIERS:
            raise unknown("modifier", mname, MODIFIERS)
        if mname in seen:
            raise UserError(f"modifier +{mname} given twice in {text.strip()!r}; allowed: each "
                            f"modifier once (observe several integrals with on=A/B)")
        seen.add(mname)
        mrec = MODIFIERS[mname]
        if mrec.kind == "field" and rec.field_modifiers_refused:
            raise UserError(f"method {name} cannot take a field modifier (+{mname}): "
                            f"{rec.field_modifiers_refused}; use +projection, or another method")
        values = bind(mrec.params, mgiven, f"modifier {mname}")
        if problem is not None:
            values = mrec.resolve(values, problem)
        mods.append(Bound(mrec, values))
    if problem is not None:
        rec.check_structure(problem.record, has_modifiers=bool(mods))
    return MethodConfig(base, tuple(mods))


def canonical(problem: Bound, method: MethodConfig) -> tuple[str, str]:
    """The canonical texts of a cell's problem and method."""
    return problem.text(), method.text()


def prepare(problem_text: str, method_text: str) -> tuple[Bound, MethodConfig]:
    """Parse and validate a cell's specs (raises UserError on bad input); a transformed problem's
    method is checked against the system it integrates."""
    problem = parse_problem(problem_text)
    target = problem.record.transformed(problem.values) or problem
    return problem, parse_method(method_text, target)
