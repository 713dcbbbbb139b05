"""Numbers written by a user: one grammar for spec options, command-line options and budgets.

A number is written in ASCII digits, without ``_`` separators: Python's ``int()`` and ``float()``
would also take ``١٠`` (Arabic-Indic digits), ``０.１`` (full-width) and ``1_0``, so they are never
applied to user text directly. Integers may be written as ``1e14`` (an integral value) where a
count is expected; every value is finite and checked against its range, and an error names the
option, the bad text and what is allowed, on one line.
"""
from __future__ import annotations

import math
import re

from gnibench.suite.foundation.errors import UserError, named

FLOAT = re.compile(r"^[+-]?([0-9]+\.?[0-9]*|\.[0-9]+)([eE][+-]?[0-9]+)?$", re.ASCII)
INT = re.compile(r"^[+-]?[0-9]+$", re.ASCII)
INT_LIMIT = 2 ** 62          # integers handed to the compiled drivers stay far from int64 overflow


def ascii_note(text: str) -> str:
    """An explanation for text that is not an ASCII number because of its characters."""
    if not text.isascii() or "_" in text:
        return " (numbers are written in ASCII digits, without _)"
    return ""


def _bad(name: str, text: str, allowed: str) -> UserError:
    plain = text and text.isascii() and text.isprintable() and " " not in text
    shown = text if plain else repr(text)               # bad -j 0, bad --steps '١٠'
    # bad --steps 0 (command line), bad steps=0 (Python), bad GNIBENCH_MAX_STEPS=inf
    return UserError(f"bad {named(name, shown)}; allowed: {allowed}{ascii_note(text)}")


def parse_float(text: str, name: str, *, low: float | None = None, high: float | None = None,
                low_open: bool = False, allowed: str | None = None) -> float:
    """A finite float in [low, high] (``low_open``: low excluded) from user text."""
    text = str(text).strip()
    allowed = allowed or _range(low, high, low_open, "a number")
    if not FLOAT.match(text):
        raise _bad(name, text, allowed)
    value = float(text)
    if not math.isfinite(value) or (low is not None and (value < low or low_open and value == low)) \
            or (high is not None and value > high):
        raise _bad(name, text, allowed)
    return value


def parse_int(text: str, name: str, *, low: int = 1, high: int = INT_LIMIT,
              allowed: str | None = None) -> int:
    """An integer in [low, high] from user text: ``1000``, or ``1e3`` when it is integral."""
    text = str(text).strip()
    allowed = allowed or f"an integer from {low} to {_show(high)}"
    if INT.match(text):
        value = int(text)
    elif FLOAT.match(text):
        x = float(text)
        if not math.isfinite(x) or x != math.floor(x) or abs(x) > 2.0 ** 63:
            raise _bad(name, text, allowed)
        value = int(x)
    else:
        raise _bad(name, text, allowed)
    if not low <= value <= high:
        raise _bad(name, text, allowed)
    return value


def _show(x: float) -> str:
    if x == INT_LIMIT:
        return "2^62"
    return f"{x:g}" if isinstance(x, float) or abs(x) >= 10 ** 6 else str(x)


def _range(low, high, low_open, what: str) -> str:
    if low is None and high is None:
        return f"{what} (finite)"
    if high is None:
        return f"{what} {'>' if low_open else '>='} {_show(low)}"
    if low is None:
        return f"{what} <= {_show(high)}"
    return f"{what} from {_show(low)}{' (excluded)' if low_open else ''} to {_show(high)}"


def option(kind: str, name: str, **bounds):
    """An argparse ``type=`` for a command-line option (``kind``: int or float); the error is a
    one-line UserError naming the option."""
    parse = parse_int if kind == "int" else parse_float

    def convert(text: str):
        return parse(text, name, **bounds)

    convert.__name__ = kind            # argparse names the type in its own messages
    return convert
