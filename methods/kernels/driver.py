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

The same template is generated three times (literal flags renamed, as ``integrate_dense`` is made
from methods/kernels/adaptive.py), so that the plain driver compiles without the others' code:

* ``integrate`` (``SECTION`` = ``GRID`` = False): a sample every ``every`` steps;
* ``integrate_grid`` (``GRID``): samples on the time grid t_k = k dt_out, k = 0, every, ... <
  ``n_out``, plus the final point, by partial steps (methods/kernels/events.py, ``grid_sample``);
* ``integrate_section`` (``SECTION``, problems with a Poincaré section): after each accepted step a
  crossing of g in (t_n, t_n+1] is located by Hénon's trick from y_n and written with the
  counters of its step; the run stops with ``STATUS_OK`` after ``st[ST_WANTED]`` crossings.

``dt_out`` and ``n_out`` are read by ``integrate_grid`` only; the slots of ``st`` are listed in
methods/kernels/slots.py.
"""
from __future__ import annotations

from gnibench.methods.kernels.free import (
    GRID,
    GRID_ULPS,
    SECTION,
    ST_FOUND,
    ST_KOUT,
    ST_ROLLBACKS,
    ST_TCOMP,
    ST_WANTED,
    STATUS_BUFFER_FULL,
    STATUS_NONFINITE,
    STATUS_OK,
    STATUS_PAUSED,
    N,
    crosses,
    grid_sample_fixed,
    henon_crossing,
    invariants,
    make_ws,
    post_step,
    project,
    section_event,
    section_g_0,
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


def partial_fixed(y, fy, sigma, par, ws, k):
    """A partial step of a fixed-step method: its own step of size sigma (time grid)."""
    return step(y, sigma, par, ws)


def integrate(y_io, st, par, h, nsteps, h_last, every, dt_out, n_out, budget, out_t, out_y, out_c):
    # st: steps done, nfev, njev, step of the last sample, started; slots of methods/kernels/slots.py
    # (GRID: next grid index, time component; SECTION: crossings found and wanted, statistics)
    ws = make_ws()
    y = to_tuple(y_io[0])
    rows = out_t.shape[0]
    row = 0
    done = int(st[0])
    nfev = st[1]
    njev = st[2]
    last_row_step = int(st[3])
    if st[4] == 0.0:
        if not SECTION:                   # a section run writes crossings only
            record_row(out_t, out_y, out_c, 0, 0.0, y, 0.0, 0.0, 0.0, 0.0)
            row = 1
        st[4] = 1.0
        if GRID:
            st[ST_KOUT] = every
    kout = int(st[ST_KOUT]) if GRID else 0
    tc = int(st[ST_TCOMP]) if GRID else -1
    g0 = section_g_0(y, par) if SECTION else 0.0
    t_final = (nsteps - 1) * h + h_last
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
        nfev_before = nfev
        njev_before = njev
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
        y_old = y
        y = post_step(y1, par)           # identification map of the problem, or the identity
        done += 1
        if SECTION:
            g1 = section_g_0(y, par)
            if crosses(g0, g1):
                ys, ts, nf = henon_crossing(y_old, (done - 1) * h,
                                            done * h if done < nsteps else t_final, par, st)
                nfev += nf
                row += section_event(ys, ts, par, st, out_t, out_y, out_c, row, done, nfev, njev,
                                     0.0)
                if st[ST_FOUND] >= st[ST_WANTED]:
                    break
            g0 = g1
        elif GRID:
            # samples at t_k = k dt_out in this step (methods/kernels/events.py); the step is
            # redone by the next call when they do not fit the buffer (identical operations)
            t = done * h if done < nsteps else t_final
            t_hi = t if tc < 0 else y[tc]
            tol = GRID_ULPS * 2.220446049250313e-16 * abs(t_hi)
            last = done == nsteps
            row_start = row
            kout_start = kout
            full = False
            while kout < n_out:
                tk = kout * dt_out
                if not (tk < t_hi - tol or (not last and tk <= t_hi + tol)):
                    break
                if row >= rows - 1:
                    full = True
                    break
                yk, sk, nf, nj, s = grid_sample_fixed(y_old, y_old, (done - 1) * h, y, t, hh, tk,
                                                      tc, par, ws, 0)
                nfev += nf
                njev += nj
                if s != STATUS_OK:
                    status = s
                    break
                record_row(out_t, out_y, out_c, row, sk, yk, done, nfev, njev, 0.0)
                row += 1
                kout += every
            if full:
                y = y_old
                done -= 1
                nfev = nfev_before
                njev = njev_before
                kout = kout_start
                row = row_start
                st[ST_ROLLBACKS] += 1.0
                status = STATUS_BUFFER_FULL
                break
            if status != STATUS_OK:
                break
            if last:
                record_row(out_t, out_y, out_c, row, t, y, done, nfev, njev, 0.0)
                row += 1
                last_row_step = done
        elif done % every == 0 or done == nsteps:
            t = done * h if done < nsteps else t_final
            record_row(out_t, out_y, out_c, row, t, y, done, nfev, njev, 0.0)
            row += 1
            last_row_step = done
    if not SECTION and status != STATUS_OK and status != STATUS_BUFFER_FULL \
            and status != STATUS_PAUSED and done > last_row_step:
        record_row(out_t, out_y, out_c, row, done * h, y, done, nfev, njev, 0.0)
        row += 1
        last_row_step = done
    store(y, y_io, 0)
    st[0] = done
    st[1] = nfev
    st[2] = njev
    st[3] = last_row_step
    if GRID:
        st[ST_KOUT] = kout
    return status, row


def eval_invariants(Y, par, rows, out):
    for r in range(rows):
        store(invariants(to_tuple(Y[r]), par), out, r)
