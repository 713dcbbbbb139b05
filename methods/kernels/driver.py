"""The fixed-step driver (template): the compiled loop every fixed-step cell runs.

After each accepted step the step modifiers (``project``) and the problem's ``post_step``
(identity unless the problem has an identification map, e.g. [B] (8.3)-(8.4)) are applied.
Samples every ``every`` steps plus the final point; stops at the first failed step
(``STATUS_NEWTON_FAILED`` from Newton or a projection) or non-finite state
(``STATUS_NONFINITE``), keeping every sample taken so far plus the last good point.

The driver is resumable, like the adaptive ones: its whole state lives in ``y_io`` (row 0: the
current state) and ``st`` (steps done, nfev, njev, step of the last sample, started), so the
facade (:mod:`gnibench.suite.cell.driver`) can call it again and again: it returns
``STATUS_PAUSED`` after ``budget`` steps (so that Python can show progress and honour Ctrl-C) and
``STATUS_BUFFER_FULL`` when fewer than two output rows are left (a sample and a failure row), and
continues with exactly the same operations.
"""
from __future__ import annotations

from gnibench.methods.kernels.free import (
    STATUS_BUFFER_FULL,
    STATUS_NONFINITE,
    STATUS_OK,
    STATUS_PAUSED,
    N,
    invariants,
    make_ws,
    post_step,
    project,
    step,
    store,
    to_tuple,
)


def record_row(out_t, out_y, out_c, row, t, y, steps, nfev, njev, rejected):
    """Write one sample: time, state and the cumulative counters."""
    out_t[row] = t
    store(y, out_y, row)
    out_c[row, 0] = steps
    out_c[row, 1] = nfev
    out_c[row, 2] = njev
    out_c[row, 3] = rejected


def integrate(y_io, st, par, h, nsteps, h_last, every, budget, out_t, out_y, out_c):
    # st: steps done, nfev, njev, step of the last sample, started
    ws = make_ws()
    y = to_tuple(y_io[0])
    rows = out_t.shape[0]
    row = 0
    done = int(st[0])
    nfev = st[1]
    njev = st[2]
    last_row_step = int(st[3])
    if st[4] == 0.0:
        record_row(out_t, out_y, out_c, 0, 0.0, y, 0.0, 0.0, 0.0, 0.0)
        row = 1
        st[4] = 1.0
    status = STATUS_OK
    stop = done + budget
    while done < nsteps:
        if rows - row < 2:
            status = STATUS_BUFFER_FULL
            break
        if done >= stop:
            status = STATUS_PAUSED
            break
        hh = h if done < nsteps - 1 else h_last
        y1, nf, nj, s = step(y, hh, par, ws)
        nfev += nf
        njev += nj
        if s != STATUS_OK:
            status = s
            break
        probe = 0.0
        for k in range(N):
            probe += y1[k] * 0.0          # 0 when finite, NaN as soon as one entry is inf or NaN
        if probe != 0.0:
            status = STATUS_NONFINITE
            break
        y1, s = project(y1, par)         # step modifiers (projection), or the identity
        if s != STATUS_OK:
            status = s
            break
        y = post_step(y1, par)           # identification map of the problem, or the identity
        done += 1
        if done % every == 0 or done == nsteps:
            t = done * h if done < nsteps else (nsteps - 1) * h + h_last
            record_row(out_t, out_y, out_c, row, t, y, done, nfev, njev, 0.0)
            row += 1
            last_row_step = done
    if status != STATUS_OK and status != STATUS_BUFFER_FULL and status != STATUS_PAUSED \
            and done > last_row_step:
        record_row(out_t, out_y, out_c, row, done * h, y, done, nfev, njev, 0.0)
        row += 1
        last_row_step = done
    store(y, y_io, 0)
    st[0] = done
    st[1] = nfev
    st[2] = njev
    st[3] = last_row_step
    return status, row


def eval_invariants(Y, par, rows, out):
    for r in range(rows):
        store(invariants(to_tuple(Y[r]), par), out, r)
