"""The adaptive driver (template): one resumable loop for every adaptive method.

The embedded pairs (Hairer's DOPRI5/DOP853 control, HNW I §II.4; templates/pair.py) and GBS
extrapolation (ODEX's order and step control, HNW I §II.9; templates/odex.py) share this loop;
what differs is the family's attempt and its step-size controller, kept apart as diffrax keeps
``AbstractStepSizeController`` apart from the solver. Each family binds
(methods/assembly/bindings.py ``ADAPTIVE_PART``):

* ``adaptive_ws()``: per-call scratch (odex: its tableau T, H_j, W_j and the attempt's
  parameters and outcome; pairs: none);
* ``controller_init(y, fy, par, h0, hmax, rtol, atol, t_end) -> (h, nfev, cs)``: the first step
  (h0, or Hairer's HINIT below) and the controller's state cs (pairs: facold; odex: the order k);
  ``controller_state(x)``: cs from its slot ``ST_CONTROL``; ``controller_clip(h, hmax)``: the
  attempt's size within hmax (odex; the pairs' controller keeps it there already);
  ``controller_prepare(ws, cs, first, last, reject, hmax)``: what the attempt needs to know of
  the controller (odex: the order k and which lines to compute; pairs: nothing);
* ``attempt(y, e, fy, h, par, ws, rtol, atol) -> (y1, e1, err, f1)``: one attempt of size h
  from y (fy = f(y); ``attempt_stages`` also returns the stages, for dense output), ``f1`` being
  f(y1) when the pair has it (FSAL), and ``attempt_outcome(ws, err) -> (kc, nfev, verdict)``:
  odex's lines used, the f-evaluations, ``ACCEPT``, ``REJECT`` or ``UNSTABLE`` (odex's stability
  check: redo with a smaller step). The pairs' attempt is a generated function of few arguments
  and their outcome a constant: a wider call cost 2-4 % of dopri5's time per attempt (measured);
* ``controller_accept(h, cs, err, reject, kc, ws, hmax) -> (h_new, cs)`` and
  ``controller_reject(h, cs, err, verdict, kc, ws, nacc) -> (h_new, cs, counted)``;
* ``partial_step``: its own step of a given size, for time-grid samples (``grid_rows``).

The loop: ``STATUS_STEP_TOO_SMALL`` when 0.1 |h| <= |t| eps; the last step lands
exactly on t_end (t + 1.01 h > t_end: h = t_end - t); after an accepted step the step modifiers
(``project``) and the problem's ``post_step`` map y_n+1, f(y_n+1) is the FSAL stage or evaluated,
and the step's samples are written: every ``every`` accepted steps plus the final point, or the
time grid (``grid_rows``), or the section crossings (``section_rows``;
templates/sampling.py). Under ``sum=compensated`` (``COMPENSATED``) the attempt adds its
increment with the carried error e of y, t is summed with its carried error e_t, and the last step
is (t_end - t) - e_t ([HLW] VIII.5; methods/summation.py).

The driver is resumable: its whole state lives in ``y_io`` (y, f(y), the carry of y) and ``st``
(the named slots of templates/slots.py), so Python can empty a full output buffer or show
progress and call again without changing a single operation (``STATUS_BUFFER_FULL``,
``STATUS_PAUSED`` after ``budget`` attempts). When a step's grid samples do not fit the buffer, the
step is undone (y, its carry, t, h, the controller's state, counters) and redone by the next call.

Each output has a module of its own in which the flags are module constants
(methods/assembly/bindings.py ``DRIVERS``), so that the plain driver compiles without the others'
code (numba drops the branches of a constant test; one driver carrying both the plain and the
dense-output loops took 50 % longer to compile, measured on kepler-3d). Python knows them by
their outputs' names:

* ``integrate_adaptive``: a sample every ``every`` accepted steps plus the final point; with a
  5th column in ``out_c``, the size of the step ending at each sample (tests/kernels/test_dense_output.py);
* ``integrate_dense`` (``DENSE_OUTPUT``, ``GRIDDED``, ``WITH_STAGES``; pairs with a continuous
  extension, methods/dense_output.py): the grid t_k = k dt_out (k = 0, every, ... < ``n_out``) plus
  t_end by dense output, as Hairer's SOLOUT does (HNW I §II.6), the steps unchanged;
* ``adaptive_grid`` (``GRID``, ``GRIDDED``): the same grid by partial steps (pairs without an
  extension or whose accepted points are not its endpoints, odex);
* ``adaptive_section`` (``SECTION``) and ``adaptive_section_dense`` (``SECTION_DENSE``,
  ``WITH_STAGES``): Poincaré section crossings by Hénon's trick or on the step's extension; the run
  stops with ``STATUS_OK`` after ``st[ST_WANTED]`` crossings.

With ``st[ST_TCOMP]`` = i >= 0 the grid's time is the state component i (the physical time t of a
transformed problem, K-S) instead of the integration variable.
"""
from __future__ import annotations

import math

from gnibench.methods.assembly.templates.slots import (
    ACCEPT,
    ROW_CARRY,
    ROW_F,
    ROW_Y,
    STATUS_BUFFER_FULL,
    STATUS_MAX_STEPS,
    STATUS_OK,
    STATUS_PAUSED,
    STATUS_STEP_TOO_SMALL,
    ST_CONTROL,
    ST_FOUND,
    ST_H,
    ST_KOUT,
    ST_LAST_ROW,
    ST_NFEV,
    ST_REJECT,
    ST_REJECTED,
    ST_ROLLBACKS,
    ST_STARTED,
    ST_STEPS,
    ST_T,
    ST_TCOMP,
    ST_T_CARRY,
    ST_WANTED,
)


def initial_step(y, fy, par, hmax, rtol, atol):
    """Hairer's HINIT: a first guess from |y|/|f| and an estimate of the second derivative."""
    dnf = 0.0
    dny = 0.0
    for i in range(N):
        sk = atol + rtol * abs(y[i])
        dnf += (fy[i] / sk) ** 2
        dny += (y[i] / sk) ** 2
    h = 1.0e-6 if (dnf <= 1.0e-10 or dny <= 1.0e-10) else math.sqrt(dny / dnf) * 0.01
    h = min(h, hmax)
    y1 = to_tuple_shift(y, h, fy)
    f1 = f(y1, par)
    der2 = 0.0
    for i in range(N):
        sk = atol + rtol * abs(y[i])
        der2 += ((f1[i] - fy[i]) / sk) ** 2
    der2 = math.sqrt(der2) / h
    der12 = max(abs(der2), math.sqrt(dnf))
    h1 = max(1.0e-6, abs(h) * 1.0e-3) if der12 <= 1.0e-15 else (0.01 / der12) ** (1.0 / IORD)
    return min(100.0 * abs(h), h1, hmax)


def first_step(y, fy, par, h0, hmax, rtol, atol):
    """The first step (h0 if given, capped by hmax, else HINIT) and the f-evaluations so far:
    f(y0), plus HINIT's probe."""
    h = min(h0, hmax)
    nfev = 1.0
    if not h0 > 0.0:
        h = initial_step(y, fy, par, hmax, rtol, atol)
        nfev = 2.0
    return h, nfev


def integrate_adaptive(y_io, st, par, t_end, h0, hmax, rtol, atol, every, dt_out, n_out, max_steps,
                       budget, out_t, out_y, out_c):
    # dt_out, n_out: the time grid (integrate_dense, adaptive_grid; the others ignore them)
    ws = adaptive_ws()
    y = to_tuple(y_io[ROW_Y])
    if COMPENSATED:
        e = to_tuple(y_io[ROW_CARRY])
    else:
        e = 0.0                            # no carry: sum=plain
    rows = out_t.shape[0]
    with_h = out_c.shape[1] > 4
    row = 0
    if st[ST_STARTED] == 0.0:
        fy = f(y, par)
        h, nf, cs = controller_init(y, fy, par, h0, hmax, rtol, atol, t_end)
        st[ST_H] = h
        st[ST_NFEV] = nf
        st[ST_CONTROL] = cs
        st[ST_T] = 0.0
        st[ST_T_CARRY] = 0.0
        st[ST_REJECT] = 0.0
        st[ST_STARTED] = 1.0
        if not SECTION:                    # a section run writes crossings only
            record_row(out_t, out_y, out_c, 0, 0.0, y, 0.0, st[ST_NFEV], 0.0, 0.0)
            if with_h:
                out_c[0, 4] = 0.0
            row = 1
        if GRIDDED:
            st[ST_KOUT] = every
    else:
        fy = to_tuple(y_io[ROW_F])
    t, et, h = st[ST_T], st[ST_T_CARRY], st[ST_H]
    cs = controller_state(st[ST_CONTROL])
    reject = st[ST_REJECT] != 0.0
    nacc, nrej, nfev = int(st[ST_STEPS]), int(st[ST_REJECTED]), st[ST_NFEV]
    kout = int(st[ST_KOUT]) if GRIDDED else 0
    tc = int(st[ST_TCOMP]) if GRIDDED else -1
    g0 = section_g_0(y, par) if SECTION else 0.0
    status = STATUS_OK
    stop = nacc + nrej + budget              # attempts in this call (STATUS_PAUSED after them)
    while True:
        if row >= rows or (GRIDDED and rows - row < 2):
            status = STATUS_BUFFER_FULL
            break
        if nacc + nrej >= max_steps:
            status = STATUS_MAX_STEPS
            break
        if nacc + nrej >= stop:
            status = STATUS_PAUSED
            break
        # the state before this attempt: a gridded step whose samples do not fit is redone
        h_start, cs_start, reject_start, nrej_start, nfev_start = h, cs, reject, nrej, nfev
        h = controller_clip(h, hmax)
        if 0.1 * abs(h) <= abs(t) * 2.220446049250313e-16 or not h > 0.0:
            status = STATUS_STEP_TOO_SMALL
            break
        last = False
        if t + 1.01 * h - t_end > 0.0:
            h = (t_end - t) - et if COMPENSATED else t_end - t
            last = True
        controller_prepare(ws, cs, nacc + nrej == 0, last, reject, hmax)
        if WITH_STAGES:
            y1, e1, err, f1, ks = attempt_stages(y, e, fy, h, par, ws, rtol, atol)
        else:
            y1, e1, err, f1 = attempt(y, e, fy, h, par, ws, rtol, atol)
            ks = 0
        kc, nf, verdict = attempt_outcome(ws, err)
        nfev += nf
        if verdict != ACCEPT:
            h, cs, counted = controller_reject(h, cs, err, verdict, kc, ws, nacc)
            reject = True
            if counted:
                nrej += 1
            continue
        y1p, pst = project(y1, par)
        if pst != STATUS_OK:
            status = pst
            break
        nacc += 1
        t_old = t
        et_old = et
        h_acc = h
        if last:
            t = t_end
            et = 0.0
        elif COMPENSATED:
            t, et = carry_sum(t, et, h)
        else:
            t = t + h
        y2 = post_step(y1p, par)
        fy_old = fy
        if FSAL and y2 == y1:            # f1 = f(y1): stale once y1 is moved
            fy = f1
        else:
            fy = f(y2, par)
            nfev += 1.0
        y_old = y
        y = y2
        e_old = e
        if COMPENSATED:                  # a moved point drops the carry (methods/summation.py)
            e = e1 if y2 == y1 else carry_zero(e1)
        h, cs = controller_accept(h, cs, err, reject, kc, ws, hmax)
        reject = False
        if SECTION:
            g1 = section_g_0(y, par)
            if crosses(g0, g1):
                wrote, nfev = section_rows(y_old, e_old, t_old, et_old, g0, y, t, g1, h_acc, par,
                                           st, ks, fy, out_t, out_y, out_c, row, nacc, nfev, 0.0,
                                           nrej)
                row += wrote
                if st[ST_FOUND] >= st[ST_WANTED]:
                    break
            g0 = g1
        elif GRIDDED:
            # samples at t_k = k dt_out in this step; with tc >= 0 the grid's time is the state
            # component tc (the physical time of a transformed problem)
            row_start = row
            kout_start = kout
            row, kout, nfev, _, status, full = grid_rows(
                y_old, e_old, fy_old, t_old, et_old, y, t, h_acc, last, kout, tc, dt_out, n_out,
                every, par, ws, kc, ks, fy, out_t, out_y, out_c, row, nacc, nfev, 0.0, nrej)
            if full:                       # redo this step in the next call, with a new buffer
                y = y_old
                e = e_old
                fy = fy_old
                t = t_old
                et = et_old
                h, cs, reject, nrej, nfev = h_start, cs_start, reject_start, nrej_start, nfev_start
                nacc -= 1
                kout = kout_start
                row = row_start
                last = False
                st[ST_ROLLBACKS] += 1.0
                status = STATUS_BUFFER_FULL
                break
            if status != STATUS_OK:
                break
            if last:
                record_row(out_t, out_y, out_c, row, t, y, nacc, nfev, 0.0, nrej)
                row += 1
                st[ST_LAST_ROW] = nacc
        elif nacc % every == 0 or last:
            record_row(out_t, out_y, out_c, row, t, y, nacc, nfev, 0.0, nrej)
            if with_h:
                out_c[row, 4] = h_acc
            row += 1
            st[ST_LAST_ROW] = nacc
        if last:
            break
    if not SECTION and status != STATUS_OK and status != STATUS_BUFFER_FULL \
            and status != STATUS_PAUSED and nacc > st[ST_LAST_ROW] and row < rows:
        record_row(out_t, out_y, out_c, row, t, y, nacc, nfev, 0.0, nrej)
        if with_h:
            out_c[row, 4] = 0.0                 # not a sample of every step: no step size
        row += 1
    store(y, y_io, ROW_Y)
    store(fy, y_io, ROW_F)
    if COMPENSATED:
        store(e, y_io, ROW_CARRY)
    st[ST_T], st[ST_T_CARRY], st[ST_H] = t, et, h
    st[ST_CONTROL] = cs
    st[ST_REJECT] = 1.0 if reject else 0.0
    st[ST_STEPS], st[ST_REJECTED], st[ST_NFEV] = nacc, nrej, nfev
    if GRIDDED:
        st[ST_KOUT] = kout
    return status, row
