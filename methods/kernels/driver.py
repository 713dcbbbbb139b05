"""The fixed-step driver (template): the compiled loop every cell runs.

After each accepted step the step modifiers (``project``) and the problem's ``post_step``
(identity unless the problem has an identification map, e.g. [B] (8.3)-(8.4)) are applied.
Samples every ``every`` steps plus the final point; stops at the first failed step (status 2 from
Newton) or non-finite state (status 1), keeping every sample taken so far plus the last good point.
"""
from __future__ import annotations

from gnibench.methods.kernels.free import N, invariants, make_ws, post_step, project, step, store, to_tuple


def record_row(out_t, out_y, out_c, row, t, y, steps, nfev, njev, rejected):
    """Write one sample: time, state and the cumulative counters."""
    out_t[row] = t
    store(y, out_y, row)
    out_c[row, 0] = steps
    out_c[row, 1] = nfev
    out_c[row, 2] = njev
    out_c[row, 3] = rejected


def integrate(y0, par, h, nsteps, h_last, every, out_t, out_y, out_c):
    ws = make_ws()
    y = to_tuple(y0)
    nfev = 0.0
    njev = 0.0
    record_row(out_t, out_y, out_c, 0, 0.0, y, 0.0, 0.0, 0.0, 0.0)
    row = 1
    status = 0
    done = 0
    last_row_step = 0
    for i in range(nsteps):
        hh = h if i < nsteps - 1 else h_last
        y1, nf, nj, st = step(y, hh, par, ws)
        nfev += nf
        njev += nj
        if st != 0:
            status = st
            break
        probe = 0.0
        for k in range(N):
            probe += y1[k] * 0.0          # 0 when finite, NaN as soon as one entry is inf or NaN
        if probe != 0.0:
            status = 1
            break
        y1, st = project(y1, par)        # step modifiers (projection), or the identity
        if st != 0:
            status = st
            break
        y = post_step(y1, par)           # identification map of the problem, or the identity
        done = i + 1
        if done % every == 0 or done == nsteps:
            t = done * h if done < nsteps else (nsteps - 1) * h + h_last
            record_row(out_t, out_y, out_c, row, t, y, done, nfev, njev, 0.0)
            row += 1
            last_row_step = done
    if status != 0 and done > last_row_step:
        record_row(out_t, out_y, out_c, row, done * h, y, done, nfev, njev, 0.0)
        row += 1
    return status, done, row


def eval_invariants(Y, par, rows, out):
    for r in range(rows):
        store(invariants(to_tuple(Y[r]), par), out, r)
