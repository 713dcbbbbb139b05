"""The one status vocabulary: kernels' return codes, tables, reports and docs all read it here.

A cell ends with a *final* status (``ok`` or one of the failures); the compiled drivers return
the integer ``code`` of a status (their templates name them ``STATUS_<NAME>``, constants emitted
into every generated module by :func:`kernel_constants`). Two codes are *internal*: the driver
stopped only to let Python empty its output buffer or look at the clock, and is called again
(never a final status). ``interrupted`` and ``error`` are set by Python (Ctrl-C; an unexpected
exception inside a cell of a matrix), ``pending`` only in the tables of an unfinished run.
"""
from __future__ import annotations

from enum import Enum


class Status(str, Enum):
    """A cell's status: its text (the value, as in the tables), kernel code, meaning and kind."""

    def __new__(cls, text: str, code: int | None, doc: str, kind: str):
        obj = str.__new__(cls, text)
        obj._value_ = text
        obj.code = code
        obj.doc = doc
        obj.kind = kind          # final | failure | internal | table
        return obj

    def __str__(self) -> str:
        return self.value

    OK = ("ok", 0, "reached the end of the horizon (or the requested section crossings)", "final")
    NONFINITE = ("nonfinite", 1, ("the state overflowed or became NaN; samples up to the last "
                                  "finite point are kept"), "failure")
    NEWTON_FAILED = ("newton_failed", 2, ("an implicit step (or a projection) did not converge in "
                                          "newton_maxit iterations"), "failure")
    MAX_STEPS = ("max_steps", 3, "an adaptive method used up max_steps before the end", "failure")
    STEP_TOO_SMALL = ("step_too_small", 4, ("an adaptive step size underflowed (stiff or "
                                            "diverging)"), "failure")
    BUFFER_FULL = ("buffer_full", 5, ("internal: the output buffer is full; the driver is called "
                                      "again with an empty one"), "internal")
    PAUSED = ("paused", 6, ("internal: one call's work budget is spent; the driver is called "
                            "again (progress, Ctrl-C)"), "internal")
    MAX_ROWS = ("max_rows", None, ("the run filled its output budget (GNIBENCH_MAX_ROWS rows or "
                                   "GNIBENCH_MAX_OUTPUT_MB of samples) and was stopped: a sampling "
                                   "grid that a stalled or runaway time keeps filling; the samples so "
                                   "far are kept"), "failure")
    INTERRUPTED = ("interrupted", None, ("stopped by the user (Ctrl-C); what was finished is "
                                         "kept"), "failure")
    ERROR = ("error", None, ("an unexpected exception inside one cell of a matrix (type and "
                             "message in the reason)"), "failure")
    PENDING = ("pending", None, "not run yet (the tables of an unfinished run)", "table")

    @classmethod
    def from_code(cls, code: int) -> Status:
        """The status of a kernel's return code."""
        for s in cls:
            if s.code == int(code):
                return s
        raise ValueError(f"unknown kernel status code {code!r}")

    @property
    def failed(self) -> bool:
        return self.kind == "failure"


KERNEL_STATUSES = tuple(s for s in Status if s.code is not None)
#: every status a table may hold, in report order
TABLE_STATUSES = tuple(s.value for s in Status if s.kind != "internal")


def kernel_constants() -> str:
    """``STATUS_<NAME> = code`` lines for a generated module (the names kernel templates use)."""
    return "".join(f"STATUS_{s.name} = {s.code}\n" for s in KERNEL_STATUSES)
