"""The fixed-step driver (template): the compiled loop every fixed-step cell runs.

After each accepted step the step modifiers (``project``) and the problem's ``post_step``
(identity unless the problem has an identification map, e.g. [B] (8.3)-(8.4)) are applied.
Samples every ``every`` steps plus the final point; stops at the first failed step
(``STATUS_NEWTON_FAILED`` from Newton or a projection) or non-finite state
(``STATUS_NONFINITE``), keeping every sample taken so far plus the last good point.

The driver is resumable, like the adaptive one: its whole state lives in ``y_io`` and ``st``
(the named slots of templates/slots.py: steps done, nfev, njev, the step of the last sample,
started; under ``sum=compensated`` the carried compensation of y in ``y_io[ROW_CARRY]``), so the
facade (:mod:`gnibench.suite.cell.drivers`) can call it again and again: it returns
``STATUS_PAUSED`` after ``budget`` steps (so that Python can show progress and honour Ctrl-C) and
``STATUS_BUFFER_FULL`` when fewer than two output rows are left (a sample and a failure row), and
continues with exactly the same operations.

The step is the method's ``step(y, h, par, ws)``, or under ``sum=compensated`` (``COMPENSATED``,
a constant of the kernel module) ``step_sum(y, e, h, par, ws)``, which adds the increment with
the carried rounding error e ([HLW] VIII.5; methods/summation.py). The time is t_n = n h (the last
step h_last), a product, not a running sum.

Each output has a module of its own in which the flags are module constants
(methods/assembly/bindings.py ``DRIVERS``), so that a driver compiles without the others' code
(numba drops the branches of a constant test); Python knows the three by their outputs' names:

* ``integrate`` (``SECTION`` = ``GRID`` = False): a sample every ``every`` steps;
* ``integrate_grid`` (``GRID``): samples on the time grid t_k = k dt_out, k = 0, every, ... <
  ``n_out``, plus the final point, by partial steps (``grid_rows``, templates/sampling.py, over
  :func:`partial_step`);
* ``integrate_section`` (``SECTION``, problems with a Poincaré section): after each accepted step a
  crossing of g in (t_n, t_n+1] is located by Hénon's trick from y_n and written with the
  counters of its step (``section_rows``); the run stops with ``STATUS_OK`` after
  ``st[ST_WANTED]`` crossings.

``dt_out`` and ``n_out`` are read by ``integrate_grid`` only.
"""
from __future__ import annotations

from gnibench.methods.assembly.templates.slots import (
    ROW_CARRY,
    ROW_Y,
    STATUS_BUFFER_FULL,
    STATUS_NONFINITE,
    STATUS_OK,
    STATUS_PAUSED,
    ST_FOUND,
    ST_KOUT,
    ST_LAST_ROW,
    ST_NFEV,
    ST_NJEV,
    ST_ROLLBACKS,
    ST_STARTED,
    ST_STEPS,
    ST_TCOMP,
    ST_WANTED,
)


def partial_step(y, e, fy, sigma, par, ws, k):
    """A partial step of a fixed-step method: its own step of size sigma (time grid) from y (+ e)
    (``partial_step`` of the fixed kind's grid output)."""
    if COMPENSATED:
        y1, _, nf, nj, s = step_sum(y, e, sigma, par, ws)
        return y1, nf, nj, s
    return step(y, sigma, par, ws)


def integrate(y_io, st, par, h, nsteps, h_last, every, dt_out, n_out, budget, out_t, out_y, out_c):
    ws = make_ws()
    y = to_tuple(y_io[ROW_Y])
    if COMPENSATED:
        e = to_tuple(y_io[ROW_CARRY])
    else:
        e = 0.0                           # no carry: sum=plain
    rows = out_t.shape[0]
    row = 0
    done = int(st[ST_STEPS])
    nfev = st[ST_NFEV]
    njev = st[ST_NJEV]
    last_row_step = int(st[ST_LAST_ROW])
    if st[ST_STARTED] == 0.0:
        if not SECTION:                   # a section run writes crossings only
            record_row(out_t, out_y, out_c, 0, 0.0, y, 0.0, 0.0, 0.0, 0.0)
            row = 1
        st[ST_STARTED] = 1.0
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
        if COMPENSATED:
            y1, e1, nf, nj, s = step_sum(y, e, hh, par, ws)
        else:
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
        y1p, s = project(y1, par)        # step modifiers (projection), or the identity
        if s != STATUS_OK:
            status = s
            break
        y_old = y
        y = post_step(y1p, par)          # identification map of the problem, or the identity
        e_old = e
        if COMPENSATED:                  # a moved point drops the carry (methods/summation.py)
            e = e1 if y == y1 else carry_zero(e1)
        done += 1
        if SECTION:
            g1 = section_g_0(y, par)
            if crosses(g0, g1):
                t = done * h if done < nsteps else t_final
                wrote, nfev = section_rows(y_old, e_old, (done - 1) * h, 0.0, g0, y, t, g1, hh,
                                           par, st, 0, y, out_t, out_y, out_c, row, done, nfev,
                                           njev, 0.0)
                row += wrote
                if st[ST_FOUND] >= st[ST_WANTED]:
                    break
            g0 = g1
        elif GRID:
            # samples at t_k = k dt_out in this step; the step is redone by the next call when
            # they do not fit the buffer (identical operations)
            t = done * h if done < nsteps else t_final
            last = done == nsteps
            row_start = row
            kout_start = kout
            row, kout, nfev, njev, status, full = grid_rows(
                y_old, e_old, y_old, (done - 1) * h, 0.0, y, t, hh, last, kout, tc, dt_out, n_out,
                every, par, ws, 0, 0, y, out_t, out_y, out_c, row, done, nfev, njev, 0.0)
            if full:
                y = y_old
                e = e_old
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
    store(y, y_io, ROW_Y)
    if COMPENSATED:
        store(e, y_io, ROW_CARRY)
    st[ST_STEPS] = done
    st[ST_NFEV] = nfev
    st[ST_NJEV] = njev
    st[ST_LAST_ROW] = last_row_step
    if GRID:
        st[ST_KOUT] = kout
    return status, row
