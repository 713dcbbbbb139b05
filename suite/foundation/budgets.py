"""Explicit budgets: how much one command may ask for before any work starts.

A request beyond a budget is refused with one line that names the limit and how to raise it
(an environment variable), instead of allocating terabytes or running for days.

==================  ===========================  ==========================================
budget              default                      raise with
==================  ===========================  ==========================================
steps per cell      10^10 (minutes to hours)     ``GNIBENCH_MAX_STEPS``
rows per cell       10^7 samples                 ``GNIBENCH_MAX_ROWS``
output memory       2048 MB per cell             ``GNIBENCH_MAX_OUTPUT_MB``
cells per run       10^5                         ``GNIBENCH_MAX_CELLS``
==================  ===========================  ==========================================

Integers handed to the compiled drivers (steps, sampling intervals, crossings) must also stay
below ``INT_LIMIT`` = 2^62, far from int64 overflow.
"""
from __future__ import annotations

import math
import os

from gnibench.suite.foundation.errors import UserError, named
from gnibench.suite.foundation.numba_settings import check_numba_settings
from gnibench.suite.foundation.numbers import INT_LIMIT, parse_int

__all__ = ["INT_LIMIT", "check_count", "check_integer", "check_limits", "check_output", "limit"]

#: the most timed runs of one cell (``repeat``: the command line, the API, experiment files)
MAX_REPEAT = 1000
_DEFAULTS = {"GNIBENCH_MAX_STEPS": 10 ** 10, "GNIBENCH_MAX_ROWS": 10 ** 7,
             "GNIBENCH_MAX_OUTPUT_MB": 2048, "GNIBENCH_MAX_CELLS": 10 ** 5}


def limit(name: str) -> int:
    """The budget ``name`` (an environment variable, or its default): a whole number from 1 to
    2^62 in ASCII digits (``1e14`` is fine; ``inf``, ``1_0``, ``١٠`` are refused)."""
    text = os.environ.get(name)
    if text is None or not text.strip():
        return _DEFAULTS[name]
    return parse_int(text, f"{name}=", allowed="a whole number from 1 to 2^62, e.g. 1e12")


def check_limits() -> None:
    """Refuse, before any work, a budget variable that is set but not a number, and a bad value
    of a numba setting gnibench depends on (:mod:`gnibench.suite.foundation.numba_settings`:
    NUMBA_DISABLE_JIT=1 would make every cell end in error)."""
    for name in _DEFAULTS:
        limit(name)
    check_numba_settings()


def check_count(value: float, what: str, budget: str, unit: str) -> None:
    """Refuse ``value`` (a planned number of steps, rows, cells) above the budget."""
    allowed = limit(budget)
    if not math.isfinite(value) or value > allowed:
        shown = "more than 10^18" if not math.isfinite(value) or value > 1e18 else f"{value:.4g}"
        raise UserError(f"{what} needs {shown} {unit}; allowed: at most {allowed:.4g} "
                        f"(raise the limit with {budget}=N)")


def check_output(rows: float, columns: int, what: str) -> None:
    """Rows budget, then the memory of the output arrays (8 bytes per number)."""
    check_count(rows, what, "GNIBENCH_MAX_ROWS", "output rows")
    megabytes = rows * columns * 8 / 2 ** 20
    allowed = limit("GNIBENCH_MAX_OUTPUT_MB")
    if megabytes > allowed:
        raise UserError(f"{what} needs {megabytes:.0f} MB of output; allowed: at most {allowed} MB "
                        f"(raise the limit with GNIBENCH_MAX_OUTPUT_MB=N, or sample less often)")


def check_integer(value, name: str, low: int = 1) -> int:
    """An integer option within [low, INT_LIMIT]."""
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= INT_LIMIT:
        raise UserError(f"bad {named(name, repr(value))}; allowed: an integer from {low} to 2^62")
    return value
