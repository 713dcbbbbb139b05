"""Parameter schemas: the one place where options are declared, validated and printed.

Problems, methods and modifiers each carry a tuple of :class:`Param`. ``gnibench list``, the spec
parser and the error messages are all generated from these records (rebound-style self-description).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from gnibench.suite.foundation.errors import UserError

# numbers in specs are ASCII: float() would also take "０.１" (full-width digits) and "0.0_5"
from gnibench.suite.foundation.numbers import FLOAT as _FLOAT
from gnibench.suite.foundation.numbers import INT as _INT
from gnibench.suite.foundation.numbers import ascii_note


@dataclass(frozen=True)
class Param:
    """One option: name, kind, default and valid range.

    kind is one of ``float``, ``int``, ``bool``, ``str``, ``floats`` (a ``/``-separated list) or
    ``names`` (a ``/``-separated list of names, e.g. integrals).
    """

    name: str
    default: Any
    doc: str
    kind: str = "float"
    low: float | None = None          # inclusive unless low_open
    high: float | None = None         # inclusive unless high_open
    low_open: bool = False
    high_open: bool = False
    choices: tuple[str, ...] | None = None
    only_if: tuple[str, Any] | None = None   # (other option, value) under which this one matters
    show_default: bool = True    # canonical text includes it even at its default value
    scaled: bool = False         # the default is in units of the problem's time scale (h, dt_out)

    def range_text(self) -> str:
        if self.choices:
            return "one of " + "|".join(self.choices)
        if self.low is None and self.high is None:
            return {"float": "any finite number", "int": "any integer", "bool": "true|false",
                    "floats": "numbers separated by /", "names": "names separated by /",
                    "str": "text"}[self.kind]
        lo = "" if self.low is None else f"{self.low:g} {'<' if self.low_open else '<='} "
        hi = "" if self.high is None else f" {'<' if self.high_open else '<='} {self.high:g}"
        return f"{lo}{self.name}{hi}"

    def parse(self, text: str, owner: str) -> Any:
        """Parse and validate one value given as text; raise UserError naming the bad value."""
        note = ascii_note(text) if self.kind in ("float", "int", "floats") else ""
        bad = UserError(f"{owner}: bad value {self.name}={text!r}; allowed: {self.range_text()}{note}")
        if self.kind == "bool":
            if text.lower() in ("true", "1", "yes"):
                return True
            if text.lower() in ("false", "0", "no"):
                return False
            raise bad
        if self.kind == "str":
            if self.choices and text not in self.choices:
                raise bad
            return text
        if self.kind == "names":
            names = tuple(x for x in text.split("/") if x)
            if not names:
                raise bad
            return names
        if self.kind == "floats":
            parts = text.split("/")
            if not all(_FLOAT.match(x) for x in parts):
                raise bad
            vals = tuple(float(x) for x in parts)
            if not all(math.isfinite(v) for v in vals):
                raise bad
            for v in vals:
                self._check_range(v, bad)
            return vals
        if not (_INT if self.kind == "int" else _FLOAT).match(text):
            raise bad
        val = int(text) if self.kind == "int" else float(text)
        if not math.isfinite(val):
            raise bad
        self._check_range(val, bad)
        return val

    def _check_range(self, v: float, bad: UserError) -> None:
        if self.low is not None and (v < self.low or (self.low_open and v == self.low)):
            raise bad
        if self.high is not None and (v > self.high or (self.high_open and v == self.high)):
            raise bad

    def format(self, value: Any) -> str:
        """Canonical text of a value: parses back to the same value (floats via repr)."""
        if self.kind == "bool":
            return "true" if value else "false"
        if self.kind in ("floats",):
            return "/".join(format_float(v) for v in value)
        if self.kind == "names":
            return "/".join(value)
        if self.kind == "float":
            return format_float(value)
        return str(value)

    def describe(self) -> dict:
        return {"name": self.name, "default": self.default, "kind": self.kind,
                "range": self.range_text(), "doc": self.doc}


def format_float(v: float) -> str:
    """Shortest text that round-trips to the same double (Python's repr), without a trailing .0."""
    s = repr(float(v))
    return s.removesuffix(".0")


def bind(params: tuple[Param, ...], given: dict[str, str], owner: str) -> dict[str, Any]:
    """Validate ``given`` (name -> text) against the schema; return name -> value with defaults."""
    by_name = {p.name: p for p in params}
    out: dict[str, Any] = {}
    for name, text in given.items():
        if name not in by_name:
            allowed = ", ".join(by_name) or "none"
            raise UserError(f"{owner}: unknown option {name!r}; allowed options: {allowed}")
        out[name] = by_name[name].parse(text, owner)
    for p in params:
        out.setdefault(p.name, p.default)
    for name in given:            # an option that does not apply would be silently dropped
        p = by_name[name]
        if not _relevant(p, out):
            key, want = p.only_if
            raise UserError(f"{owner}: option {name} applies only with {key}="
                            f"{by_name[key].format(want)}; drop it or set {key}")
    return out


@dataclass(frozen=True)
class Bound:
    """A registry record with validated option values."""

    record: Any
    values: dict[str, Any]

    @property
    def id(self) -> str:
        return self.record.id

    def options(self) -> dict[str, str]:
        """The options of the canonical text, name -> value text: relevant, non-None values in
        schema order; options marked ``show_default=False`` (solver tuning such as
        newton_maxit) only when not at their default."""
        out = {}
        for p in self.record.params:
            v = self.values.get(p.name)
            if v is None or not _relevant(p, self.values):
                continue
            if not p.show_default and v == p.default:
                continue
            out[p.name] = p.format(v)
        return out

    def text(self) -> str:
        """Canonical ``id:key=value,...`` (:meth:`options`)."""
        parts = [f"{k}={v}" for k, v in self.options().items()]
        return self.record.id + (":" + ",".join(parts) if parts else "")


def _relevant(p: Param, values: dict[str, Any]) -> bool:
    if p.only_if is None:
        return True
    key, want = p.only_if
    return values.get(key) == want
