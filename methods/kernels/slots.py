"""The layout of ``st``, the resumable state every compiled driver keeps between calls.

One array of ``STATE`` floats serves every driver (fixed step, embedded pairs, odex, and their
dense-output, time-grid and section variants): slots 0..8 belong to the driver's own loop
(methods/kernels/driver.py, adaptive.py, extrapolation.py), slot 9 is the next grid index of a
time grid, and the rest are the run options and statistics of the variants. Python sets the run
options (``ST_TCOMP``, ``ST_WANTED``) before the first call and reads the statistics after the
last one (:mod:`gnibench.suite.cell.sections`, :mod:`gnibench.suite.cell.timegrid`). The names are
emitted as constants into every generated module (:func:`slot_constants`), so the templates and
Python read the same numbers.
"""
from __future__ import annotations

SLOTS = {
    "ST_KOUT": 9,         # next grid index k (samples at t_k = k dt_out)
    "ST_TCOMP": 10,       # run option: state component that is the time of the grid (-1: the
                          # integration variable; K-S: the physical time t of the s-system)
    "ST_FOUND": 11,       # section crossings written so far
    "ST_WANTED": 12,      # run option: stop (STATUS_OK) after this many crossings
    "ST_NEWTON": 13,      # largest number of Newton iterations of the dense locator
    "ST_SUBSTEPS": 14,    # largest number m of DOP853 substeps of Hénon's locator
    "ST_MAX_G": 15,       # largest |g| at a written crossing
    "ST_LOC_NFEV": 16,    # f-evaluations spent by the locators (included in nfev)
    "ST_ROLLBACKS": 17,   # steps redone because a step's grid points did not fit the buffer
    "ST_WALKS": 18,       # crossings Hénon's trick reached after a walk in time (turning point)
    "ST_HENON_FAILED": 19,  # crossings where neither way was valid (the direct result is kept)
}
STATE = 20

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

#: a grid time within GRID_ULPS ulps of a step end is that step end (no partial step)
GRID_ULPS = 4.0


def slot_constants() -> str:
    """``ST_<NAME> = index`` lines (and GRID_ULPS) for a generated module."""
    return "".join(f"{k} = {v}\n" for k, v in SLOTS.items()) + f"GRID_ULPS = {GRID_ULPS!r}\n"
