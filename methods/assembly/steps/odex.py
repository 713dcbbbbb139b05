"""GBS extrapolation (the ``extrapolation`` family, ODEX): its fixed step and its adaptive attempt.

The method's data (the step-number sequence, ODEX's constants) is methods/extrapolation.py; the
code is templates/odex.py (Gragg's midpoint rule, Aitken-Neville, ODEX's order and step control),
copied with the constants of the cell: the sequence up to the columns it uses, the work per line,
and ``IORD`` = ODEX's order for the HINIT heuristic (templates/adaptive.py). Fixed step
(``adaptive=false``): T_kk of k columns, ``step``/``step_sum``. Adaptive: ODEX's attempt and
controller for the adaptive loop, the small pieces written into it by numba's inliner.
"""
from __future__ import annotations

from gnibench.methods.assembly.source import INLINE, INTERNAL, constants, copy, tup
from gnibench.methods.assembly.templates import adaptive, odex

FIXED = ((odex.gragg_column, INLINE), (odex.neville, INLINE), (odex.make_ws, INTERNAL),
         (odex.fixed_increment, INTERNAL), (odex.step, INTERNAL), (odex.step_sum, INTERNAL),
         (odex.solution, INLINE))
ADAPTIVE = ((adaptive.initial_step, INLINE), (adaptive.first_step, INLINE),
            (odex.column, INTERNAL), (odex.adaptive_ws, INLINE), (odex.controller_init, INLINE),
            (odex.controller_state, INLINE), (odex.controller_clip, INLINE),
            (odex.controller_prepare, INLINE), (odex.attempt, INLINE),
            (odex.attempt_outcome, INLINE), (odex.controller_accept, INLINE),
            (odex.controller_reject, INLINE), (odex.partial_step, INTERNAL))


def write_odex(data):
    """The writer of an extrapolation method's cell (``data``: its Extrapolation record)."""

    def write(ctx) -> str:
        v = ctx.values
        kmax = int(v.get("kmax", 9)) if v.get("adaptive") else 0
        k_fixed = int(v.get("k", 4))
        size = max(kmax, k_fixed)
        text = constants(NJ=data.sequence[:size], WORK_A=data.work(size), KMAX=kmax,
                         K_FIXED=k_fixed, MSTAB=data.mstab, JSTAB=data.jstab, SAFE1=data.safe1,
                         SAFE2=data.safe2, SAFE3=data.safe3, FAC1=data.fac1, FAC2=data.fac2,
                         FAC3=data.fac3, FAC4=data.fac4, UROUND=2.3e-16,
                         IORD=data.hinit_order)
        n = ctx.n
        text += (f"\n{INLINE}\ndef to_tuple_shift(y, h, v):\n"
                 f"    return {tup(f'y[{i}] + h * v[{i}]' for i in range(n))}\n"
                 f"\n{INLINE}\ndef scaled(a, v):\n    return {tup(f'a * v[{i}]' for i in range(n))}\n"
                 + "".join(copy(fn, role) for fn, role in FIXED))
        if kmax:
            text += constants(FSAL=False) + "".join(copy(fn, role) for fn, role in ADAPTIVE)
        return text
    return write
