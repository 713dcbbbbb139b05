"""The batched driver (template): the orbits of an ensemble in one compiled call.

A compiled loop over initial conditions that calls the cell module's own single-orbit driver
(``DRIVER``: ``integrate``, ``integrate_grid``, ``integrate_adaptive``, ``integrate_dense`` or
``adaptive_grid``) once per orbit, each with a fresh resumable state (``y_io``, ``st``: the slots
of methods/kernels/slots.py, the grid's time component ``tcomp`` set as Python sets it), its own
run-time parameters (a row of ``PAR``: a modifier's H0 is the orbit's) and its own output rows
(``out_t[i]``, ``out_y[i]``, ``out_c[i]``, sized for the whole horizon), with an unlimited work
budget: the orbit runs exactly the operations a single cell of that initial condition runs, so
its samples are the same bits. ``rows[i]`` and ``status[i]`` receive what the driver returns; the
counters are in the rows. Orbits ``first .. first + count - 1`` are run, so that Python can call
it on slices of the ensemble and honour Ctrl-C and show progress between calls
(:mod:`gnibench.suite.cell.batch`).

Two copies are generated into an ensemble cell's module, and only there (``batch_<driver>`` for
the fixed-step and the adaptive argument lists; :func:`gnibench.suite.cell.codegen.module_source`
with ``batched``): a cell that is not an ensemble compiles nothing more.
"""
from __future__ import annotations

import numpy as np
from gnibench.methods.kernels.free import N, ROW_Y, ST_TCOMP

STATE = Y_ROWS = 0                      # literal in the generated copy (methods/kernels/slots.py)
UNLIMITED = 1 << 62


def DRIVER(*args):  # noqa: N802 - renamed to the single-orbit driver in the generated copy
    raise RuntimeError("kernel template called outside a generated module")


def batch_fixed(Y0, PAR, first, count, h, nsteps, h_last, every, dt_out, n_out, tcomp, out_t,
                out_y, out_c, rows, status):
    for i in range(first, first + count):
        y_io = np.zeros((Y_ROWS, N))
        for k in range(N):
            y_io[ROW_Y, k] = Y0[i, k]
        st = np.zeros(STATE)
        st[ST_TCOMP] = tcomp
        s, r = DRIVER(y_io, st, PAR[i], h, nsteps, h_last, every, dt_out, n_out, UNLIMITED,
                      out_t[i], out_y[i], out_c[i])
        status[i] = s
        rows[i] = r


def batch_adaptive(Y0, PAR, first, count, t_end, h0, hmax, rtol, atol, every, dt_out, n_out,
                   max_steps, tcomp, out_t, out_y, out_c, rows, status):
    for i in range(first, first + count):
        y_io = np.zeros((Y_ROWS, N))
        for k in range(N):
            y_io[ROW_Y, k] = Y0[i, k]
        st = np.zeros(STATE)
        st[ST_TCOMP] = tcomp
        s, r = DRIVER(y_io, st, PAR[i], t_end, h0, hmax, rtol, atol, every, dt_out, n_out,
                      max_steps, UNLIMITED, out_t[i], out_y[i], out_c[i])
        status[i] = s
        rows[i] = r


def batch_source(driver: str, adaptive: bool) -> str:
    """The batched copy of the single-orbit driver ``driver`` (``adaptive``: of the adaptive
    loop's argument list): ``batch_<driver>``, compiled with numba's own njit and the error
    model of the module's header (the header's njit treats a name it does not list as internal;
    the header of every module stays as it is)."""
    from gnibench.methods.kernels.slots import STATE, Y_ROWS
    from gnibench.suite.foundation.templates import template

    func = batch_adaptive if adaptive else batch_fixed
    text = template(func, {func.__name__: f"batch_{driver}", "DRIVER": driver,
                           "STATE": str(STATE), "Y_ROWS": str(Y_ROWS),
                           "UNLIMITED": str(UNLIMITED)})
    return text.replace("@njit(cache=True)", "@_njit(error_model='numpy', cache=True)", 1)

