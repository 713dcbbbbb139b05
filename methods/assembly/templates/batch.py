"""The batched loops (templates): the orbits of an ensemble in one compiled call.

A compiled loop over initial conditions that calls the module's own single-orbit loop (the fixed
kind's ``integrate`` of templates/fixed.py, the adaptive kind's ``integrate_adaptive`` of
templates/adaptive.py, with the flags of the module's output: samples, time grid, dense grid)
once per orbit, each with a fresh resumable state (``y_io``, ``st``: the slots of
templates/slots.py, the grid's time component ``ST_TCOMP`` set as Python sets it for one cell), its
own run-time parameters (a row of ``PAR``: a modifier's H0 is the orbit's, [B] (2.5)) and its own
output rows (``out_t[i]``, ``out_y[i]``, ``out_c[i]``, sized for the whole horizon), with an
unlimited work budget: the orbit runs exactly the operations a single cell of that initial
condition runs, so its samples are the same bits. ``rows[i]`` and ``status[i]`` receive what the
loop returns; the counters are in the rows. Orbits ``first .. first + count - 1`` are run, so that
Python can call it on slices of the ensemble, honour Ctrl-C and show progress between calls
(:mod:`gnibench.suite.cell.batch`).

A batched output (methods/assembly/bindings.py ``DriverKind.batch``) copies the kind's loop as an
``@internal`` function and this kind's batched loop as the module's ``@entry``: a cell that is not
an ensemble compiles nothing more. ``STATE`` and ``Y_ROWS`` are constants of such a module, and
:func:`orbit_state` an ``@inline`` function.
"""
from __future__ import annotations

import numpy as np
from gnibench.methods.assembly.templates.slots import ROW_Y, ST_TCOMP, STATE, Y_ROWS


def orbit_state(Y0, i, tcomp):
    # the resumable state of orbit i before its first call, as Python sets it for one cell
    y_io = np.zeros((Y_ROWS, N))
    for k in range(N):
        y_io[ROW_Y, k] = Y0[i, k]
    st = np.zeros(STATE)
    st[ST_TCOMP] = tcomp
    return y_io, st


def batch_fixed(Y0, PAR, first, count, h, nsteps, h_last, every, dt_out, n_out, tcomp, out_t,
                out_y, out_c, rows, status):
    for i in range(first, first + count):
        y_io, st = orbit_state(Y0, i, tcomp)
        s, r = integrate(y_io, st, PAR[i], h, nsteps, h_last, every, dt_out, n_out, 1 << 62,
                         out_t[i], out_y[i], out_c[i])
        status[i] = s
        rows[i] = r


def batch_adaptive(Y0, PAR, first, count, t_end, h0, hmax, rtol, atol, every, dt_out, n_out,
                   max_steps, tcomp, out_t, out_y, out_c, rows, status):
    for i in range(first, first + count):
        y_io, st = orbit_state(Y0, i, tcomp)
        s, r = integrate_adaptive(y_io, st, PAR[i], t_end, h0, hmax, rtol, atol, every, dt_out,
                                  n_out, max_steps, 1 << 62, out_t[i], out_y[i], out_c[i])
        status[i] = s
        rows[i] = r
