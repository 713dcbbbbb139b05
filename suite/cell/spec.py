"""Spec strings: one syntax on the CLI, in experiment files and in tables.

Grammar (public contract, docs: reference, "Spec strings")::

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
from gnibench.suite.foundation.errors import UserError, named, unknown
from gnibench.suite.foundation.params import Bound, bind

_MODIFIER_SPLIT = re.compile(r"\+(?=[A-Za-z])")
_ID = re.compile(r"^[A-Za-z][A-Za-z0-9_-]*$")


def parse_item(text: str, what: str) -> tuple[str, dict[str, str]]:
    """Split ``id:key=value,...`` into the id and a dict of raw option texts (surrounding spaces
    are dropped; a line break or another control character anywhere, also at the end, is
    refused)."""
    bad = next((c for c in text if not c.isprintable()), None)
    if bad is not None:
        raise UserError(f"bad {what} spec {text!r}: it contains {bad!r}; allowed: one line, no "
                        f"control characters")
    text = text.strip()
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


def split_list(text: str, name: str = "--metrics") -> list[str]:
    """Split a comma-separated list of specs (``eta,growth:of=H,window=1/2,precession``) at the
    commas that start a new spec (a comma followed by an id that is not followed by ``=``);
    an empty spec is refused (``name``: how the user wrote the list)."""
    parts: list[str] = []
    for piece in text.split(","):
        if not piece.strip():
            raise UserError(f"bad {named(name, repr(text))}: an empty spec between commas; allowed: specs "
                            f"separated by commas, e.g. eta,growth:of=H")
        if parts and "=" in piece.partition(":")[0]:
            parts[-1] += "," + piece          # an option of the previous spec
        else:
            parts.append(piece)
    return parts


def split_method(text: str) -> list[str]:
    """Split a method spec into its base and modifier parts (as written: :func:`parse_item`
    drops the spaces around each and refuses control characters)."""
    return _MODIFIER_SPLIT.split(text)


@dataclass(frozen=True)
class MethodConfig:
    """A base method and its modifiers, each bound to its option values.

    Picklable: its records travel as references to their registries
    (:mod:`gnibench.suite.foundation.registries`)."""

    base: Bound
    modifiers: tuple[Bound, ...] = ()

    def text(self) -> str:
        return "+".join([self.base.text()] + [m.text() for m in self.modifiers])

    @property
    def id(self) -> str:
        return self.base.id

    @property
    def kind(self) -> str:
        """How the base method runs: ``compiled``, ``external`` or ``python`` (``Method.kind``)."""
        return self.base.record.kind

    def family(self) -> Family:
        """The method's family: see :class:`Family`."""
        rec, values = self.base.record, self.base.values
        shown = self.base.options()
        adaptive = values.get("adaptive") is True or getattr(rec, "adaptive", False) is True
        sweep = next((k for k in ("h", "rtol", "tol", "epsilon") if k in shown), "")
        if sweep == "h" and adaptive:
            sweep = ""
        defaults = {p.name: p.default for p in rec.params}
        keep = [f"{k}={v}" for k, v in shown.items()
                if k not in SWEEP and k not in QUIET and not (k in defaults
                                                               and values[k] == defaults[k])]
        label = "+".join([rec.id + (":" + ",".join(keep) if keep else "")]
                         + [m.text() for m in self.modifiers])
        value = float(values[sweep]) if sweep else float("nan")
        return Family(label, sweep, value, adaptive)


#: options a work-precision sweep varies: they do not name a family
SWEEP = ("h", "rtol", "atol", "tol", "epsilon")
#: options that do not change a method's numbers (a step budget, the output grid of external
#: engines): left out of the family's label
QUIET = ("max_steps", "dt_out")


@dataclass(frozen=True)
class Family:
    """A method's family: the cells of one method that differ only in its step size or tolerance
    (a work-precision curve, a row of a league table).

    ``label`` is the canonical method spec without its sweep options (:data:`SWEEP`), without
    the options of :data:`QUIET` and without options left at their defaults, modifiers kept, e.g.
    ``dopri5:adaptive=true,rtol=1e-08,atol=1e-08`` -> ``dopri5``,
    ``merson:adaptive=true,rtol=1e-05,atol=1e-05`` -> ``merson:adaptive=true``,
    ``heyoka-taylor:dt_out=0.01,tol=1e-10,precision=long double`` -> ``heyoka-taylor:precision=long
    double``; ``sweep`` the option swept (``h``, ``rtol``, ``tol``, ``epsilon``, or "" when nothing
    is: an adaptive method's h), ``value`` its value (NaN when none); ``adaptive``: the method
    chooses its own steps (option ``adaptive``, or an adaptive external engine)."""

    label: str
    sweep: str
    value: float
    adaptive: bool



# -- the structure of a spec text, without the registries (the edge: an experiment's ``vary``) --

@dataclass(frozen=True)
class Item:
    """One part of a spec text: its id and its options as written (texts, in order)."""

    id: str
    options: tuple[tuple[str, str], ...] = ()

    @property
    def given(self) -> dict[str, str]:
        return dict(self.options)

    def text(self) -> str:
        return self.id + (":" + ",".join(f"{k}={v}" for k, v in self.options) if self.options
                          else "")

    def without(self, *keys: str) -> Item:
        return Item(self.id, tuple((k, v) for k, v in self.options if k not in keys))

    def with_options(self, options: dict[str, str]) -> Item:
        """The item with these options set (replaced in place, or appended)."""
        given = {**self.given, **options}
        return Item(self.id, tuple(given.items()))


@dataclass(frozen=True)
class Structure:
    """A spec text split into its parts: ``base`` (the problem or base method) and the modifiers.

    A pure function of the text (:func:`structure`): no registry is consulted, so it works on the
    texts of any table, also for methods this process has not loaded."""

    base: Item
    modifiers: tuple[Item, ...] = ()

    @property
    def id(self) -> str:
        return self.base.id

    def modifier(self, id: str) -> Item | None:
        return next((m for m in self.modifiers if m.id == id), None)

    def text(self) -> str:
        return "+".join([self.base.text()] + [m.text() for m in self.modifiers])

    def without(self, *keys: str) -> Structure:
        """The spec without these options of its base."""
        return Structure(self.base.without(*keys), self.modifiers)


def structure(text: str, what: str = "method") -> Structure:
    """The parts of a spec text (``what``: ``problem``, ``method``, ``metric``, ``reference``;
    only a method has modifiers). Raises UserError on text that is not spec syntax."""
    parts = [text] if what != "method" else split_method(text)
    items = []
    for i, part in enumerate(parts):
        name, given = parse_item(part, what if i == 0 else "modifier")
        items.append(Item(name, tuple(given.items())))
    return Structure(items[0], tuple(items[1:]))


def with_options(spec: str, target: str, options: dict[str, str]) -> str:
    """The spec with the options of ``target`` ('problem', 'method' = the base, or a modifier id)
    set to the given texts; unchanged when ``target`` is a modifier the spec does not have."""
    s = structure(spec, "problem" if target == "problem" else "method")
    if target in ("problem", "method"):
        return Structure(s.base.with_options(options), s.modifiers).text()
    return Structure(s.base, tuple(m.with_options(options) if m.id == target else m
                                   for m in s.modifiers)).text()


def parse_problem(text: str) -> Bound:
    """Resolve a PROBLEM spec against the problem registry."""
    from gnibench.problems import REGISTRY

    name, given = parse_item(text, "problem")
    if name not in REGISTRY:
        _discover()                      # GNIBENCH_LOAD and entry points, once per process
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


def _discover() -> None:
    """User definitions of ``GNIBENCH_LOAD`` and the installed entry points
    (:mod:`gnibench.suite.cell.user`), looked for the first time an id is unknown."""
    from gnibench.suite.cell.user.loader import discover

    discover()


def _integral_names(rec) -> list[str]:
    from gnibench.problems.codegen import problem_meta

    return list(problem_meta(rec)["integrals"])


def parse_method(text: str, problem: Bound | None = None) -> MethodConfig:
    """Resolve a METHOD spec; with a problem, modifiers and structure needs are checked against it."""
    from gnibench.methods import ALIASES, METHODS, MODIFIERS

    parts = split_method(text)
    name, given = parse_item(parts[0], "method")
    name = ALIASES.get(name, name)
    if name not in METHODS and name not in MODIFIERS:
        _discover()                      # GNIBENCH_LOAD and entry points, once per process
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


def prepare(problem: str | Bound, method: str | MethodConfig) -> tuple[Bound, MethodConfig]:
    """Parse and validate a cell's specs, given as text or as typed values (raises UserError on
    bad input); a transformed problem's method is checked against the system it integrates."""
    if isinstance(problem, str):
        problem = parse_problem(problem)
    elif not isinstance(problem, Bound) or getattr(problem.record, "registry", "") != "problem":
        raise UserError(f"bad problem {problem!r}; allowed: a PROBLEM spec string or a parsed "
                        f"problem (gnibench.suite.cell.spec.parse_problem)")
    target = problem.record.transformed(problem.values) or problem
    if isinstance(method, str):
        return problem, parse_method(method, target)
    if not isinstance(method, MethodConfig):
        raise UserError(f"bad method {method!r}; allowed: a METHOD spec string or a parsed method "
                        f"(gnibench.suite.cell.spec.parse_method)")
    return problem, _checked(method, target)


def _checked(method: MethodConfig, problem: Bound) -> MethodConfig:
    """A method parsed without (or for another) problem, checked against this one: its
    modifiers resolved for the problem (observed integrals, targets), its structure needs."""
    rec = method.base.record
    mods = []
    for m in method.modifiers:
        if m.record.kind == "field" and rec.field_modifiers_refused:
            raise UserError(f"method {rec.id} cannot take a field modifier (+{m.id}): "
                            f"{rec.field_modifiers_refused}; use +projection, or another method")
        mods.append(Bound(m.record, m.record.resolve(dict(m.values), problem)))
    rec.check_structure(problem.record, has_modifiers=bool(mods))
    return MethodConfig(method.base, tuple(mods))
