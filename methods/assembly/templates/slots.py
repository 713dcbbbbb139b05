"""The resumable state of every compiled driver: the named slots of ``st`` and rows of ``y_io``.

Every compiled driver (the fixed-step loop of templates/fixed.py, the adaptive loop of
templates/adaptive.py shared by the embedded pairs and odex, and their dense-output,
time-grid and section variants) keeps its whole state between calls in two arrays, so that Python
can empty a full output buffer, show progress or honour Ctrl-C and call again without changing a
single operation:

* ``y_io`` (``Y_ROWS`` x N): the current state y_n (``ROW_Y``), f(y_n) of an adaptive driver
  (``ROW_F``, its first stage of the next step), and the carried compensation of y_n under
  ``sum=compensated`` (``ROW_CARRY``, [HLW] VIII.5, methods/summation.py);
* ``st`` (``STATE`` floats): the slots below. One layout serves both kinds; a slot a kind does not
  use stays 0. Python sets the run options (``ST_TCOMP``, ``ST_WANTED``) before the first call and
  reads the counters and statistics after any call (:mod:`gnibench.suite.cell.drivers`).

The names are emitted as constants into every generated module (:func:`slot_constants`), so the
templates and Python read the same numbers.
"""
from __future__ import annotations

from gnibench.suite.foundation.status import KERNEL_STATUSES, Status

SLOTS = {
    "ST_STARTED": 0,      # 1 once the first call has written the initial point
    "ST_STEPS": 1,        # accepted steps (fixed step: steps done)
    "ST_NFEV": 2,         # f-evaluations so far (partial steps and locators included)
    "ST_NJEV": 3,         # Jacobian evaluations (implicit methods, fixed step)
    "ST_REJECTED": 4,     # rejected attempts (adaptive; embedded pairs count those after the 1st
                          # accepted step, as Hairer's codes do)
    "ST_LAST_ROW": 5,     # steps at the last sample written (a failure row is added after it)
    "ST_T": 6,            # adaptive: the time t_n reached (fixed step: t_n = n h, not stored)
    "ST_H": 7,            # adaptive: the size of the next attempt
    "ST_CONTROL": 8,      # adaptive: the step-size controller's state (embedded pairs: facold of
                          # Hairer's PI control; odex: the order k, the number of lines)
    "ST_REJECT": 9,       # adaptive: 1 when the last attempt was rejected
    "ST_T_CARRY": 10,     # adaptive under sum=compensated: the carried rounding error of t_n
    "ST_KOUT": 11,        # next grid index k (samples at t_k = k dt_out)
    "ST_TCOMP": 12,       # run option: state component that is the time of the grid (-1: the
                          # integration variable; K-S: the physical time t of the s-system)
    "ST_FOUND": 13,       # section crossings written so far
    "ST_WANTED": 14,      # run option: stop (STATUS_OK) after this many crossings
    "ST_NEWTON": 15,      # largest number of Newton iterations of the dense locator
    "ST_SUBSTEPS": 16,    # largest number m of DOP853 substeps of Hénon's locator
    "ST_MAX_G": 17,       # largest |g| at a written crossing
    "ST_LOC_NFEV": 18,    # f-evaluations spent by the locators (included in nfev)
    "ST_ROLLBACKS": 19,   # steps redone because a step's grid points did not fit the buffer
    "ST_WALKS": 20,       # crossings Hénon's trick reached after a walk in time (turning point)
    "ST_HENON_FAILED": 21,  # crossings where neither way was valid (the direct result is kept)
}
STATE = 22

ROWS = {
    "ROW_Y": 0,           # the current state y_n
    "ROW_F": 1,           # adaptive: f(y_n)
    "ROW_CARRY": 2,       # sum=compensated: the carried rounding error of y_n (0 otherwise)
}
Y_ROWS = 3

ST_STARTED = SLOTS["ST_STARTED"]
ST_STEPS = SLOTS["ST_STEPS"]
ST_NFEV = SLOTS["ST_NFEV"]
ST_NJEV = SLOTS["ST_NJEV"]
ST_REJECTED = SLOTS["ST_REJECTED"]
ST_LAST_ROW = SLOTS["ST_LAST_ROW"]
ST_T = SLOTS["ST_T"]
ST_H = SLOTS["ST_H"]
ST_CONTROL = SLOTS["ST_CONTROL"]
ST_REJECT = SLOTS["ST_REJECT"]
ST_T_CARRY = SLOTS["ST_T_CARRY"]
ST_KOUT = SLOTS["ST_KOUT"]
ST_TCOMP = SLOTS["ST_TCOMP"]
ST_FOUND = SLOTS["ST_FOUND"]
ST_WANTED = SLOTS["ST_WANTED"]
ST_NEWTON = SLOTS["ST_NEWTON"]
ST_SUBSTEPS = SLOTS["ST_SUBSTEPS"]
ST_MAX_G = SLOTS["ST_MAX_G"]
ST_LOC_NFEV = SLOTS["ST_LOC_NFEV"]
ST_ROLLBACKS = SLOTS["ST_ROLLBACKS"]
ST_WALKS = SLOTS["ST_WALKS"]
ST_HENON_FAILED = SLOTS["ST_HENON_FAILED"]
ROW_Y = ROWS["ROW_Y"]
ROW_F = ROWS["ROW_F"]
ROW_CARRY = ROWS["ROW_CARRY"]

#: the verdicts of an adaptive attempt (templates/adaptive.py): accept; reject (the
#: controller picks a smaller step); unstable (odex's stability check failed: h * SAFE3)
VERDICTS = {"ACCEPT": 0, "REJECT": 1, "UNSTABLE": 2}
ACCEPT, REJECT, UNSTABLE = VERDICTS["ACCEPT"], VERDICTS["REJECT"], VERDICTS["UNSTABLE"]

#: the kernel codes of :class:`~gnibench.suite.foundation.status.Status` the templates return
STATUSES = {f"STATUS_{s.name}": s.code for s in KERNEL_STATUSES}
STATUS_OK = Status.OK.code
STATUS_NONFINITE = Status.NONFINITE.code
STATUS_NEWTON_FAILED = Status.NEWTON_FAILED.code
STATUS_MAX_STEPS = Status.MAX_STEPS.code
STATUS_STEP_TOO_SMALL = Status.STEP_TOO_SMALL.code
STATUS_BUFFER_FULL = Status.BUFFER_FULL.code
STATUS_PAUSED = Status.PAUSED.code

#: a grid time within GRID_ULPS ulps of a step end is that step end (no partial step)
GRID_ULPS = 4.0


def slot_constants() -> str:
    """The lines ``NAME = value`` of every constant above, for a kernel module: the templates
    import them from here (so that they are valid Python), the module holds their values in its
    own text (so that its hash, the key of its cache files, covers them)."""
    return ("".join(f"{k} = {v}\n" for k, v in {**STATUSES, **SLOTS, **ROWS, **VERDICTS}.items())
            + f"GRID_ULPS = {GRID_ULPS!r}\n")
