"""Gragg-Bulirsch-Stoer extrapolation with adaptive order and step, as in Hairer's ODEX.

The method is data: the step-number sequence n_j and ODEX's controller constants (HNW I, §II.9).
Column j of the tableau is Gragg's midpoint rule with n_j substeps and the smoothing step
(HNW (9.13)), extrapolated by Aitken-Neville in h² (HNW (9.10)); with the harmonic sequence
n_j = 2j the value T_kk has order 2k (HNW Theorem II.9.1). Adaptive mode (the default) runs
ODEX's order and step-size control (methods/kernels/extrapolation.py); ``adaptive=false`` takes
fixed steps h with k columns, order 2k. ``sum=compensated`` adds the extrapolated increment to y
with the carried rounding error (methods/summation.py).
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass

from gnibench.methods.base import Method, adaptive_params
from gnibench.methods.events import grid_functions, variant
from gnibench.methods.kernels import adaptive, extrapolation
from gnibench.suite.foundation.params import Param
from gnibench.suite.foundation.templates import template


@dataclass(frozen=True)
class Extrapolation:
    """Step-number sequence and ODEX's controller constants (its defaults, HNW I §II.9)."""

    sequence: tuple[int, ...]   # n_1, n_2, ...: even (Gragg's expansion in h²), increasing
    safe1: float = 0.65         # H_j = h / fac_j, fac_j = (err_j / SAFE1)^(1/(2j-1)) / SAFE2
    safe2: float = 0.94
    safe3: float = 0.5          # step reduction after an instability ("ATOV")
    fac1: float = 0.02          # fac_j is kept in [FAC1^(1/(2j-1)), FAC2 / FAC1^(1/(2j-1))]
    fac2: float = 4.0
    fac3: float = 0.8           # lower the order if W_{k-1} < FAC3 W_k
    fac4: float = 0.9           # raise the order if W_k < FAC4 W_{k-1}
    mstab: int = 1              # stability check on the first MSTAB substeps ...
    jstab: int = 2              # ... of the first JSTAB lines
    hinit_order: int = 5        # order assumed by the HINIT initial-step heuristic (h0 = 0)

    def __post_init__(self):
        n = self.sequence
        if any(x <= 0 or x % 2 for x in n):
            raise ValueError("step numbers must be positive and even (expansion in h²)")
        if any(b <= a for a, b in itertools.pairwise(n)):
            raise ValueError("step numbers must increase")

    def work(self, k: int) -> tuple[float, ...]:
        """A_1..A_k: f evaluations of lines 1..k, f(y0) included (A_1 = n_1 + 1, A_j = A_{j-1} + n_j)."""
        a = [self.sequence[0] + 1.0]
        for nj in self.sequence[1:k]:
            a.append(a[-1] + nj)
        return tuple(a)


def harmonic(kmax: int) -> tuple[int, ...]:
    """ODEX's default sequence 2, 4, 6, 8, ... (NSEQU = 1)."""
    return tuple(2 * j for j in range(1, kmax + 1))


KMAX_LIMIT = 16
#: the controller's small pieces, written into the loop (suite/foundation/inline.py)
INLINE = {"adaptive_ws", "controller_init", "controller_state", "controller_clip",
          "controller_prepare", "attempt", "attempt_outcome", "controller_accept",
          "controller_reject"}
ODEX = Extrapolation(sequence=harmonic(KMAX_LIMIT))


def _generate(data: Extrapolation):
    def generate(ctx) -> str:
        v = ctx.values
        kmax = int(v.get("kmax", 9)) if v.get("adaptive") else 0
        k_fixed = int(v.get("k", 4))
        size = max(kmax, k_fixed)
        nj = data.sequence[:size]
        consts = (f"\nNJ = {nj!r}\nWORK_A = {data.work(size)!r}\nKMAX = {kmax}\n"
                  f"K_FIXED = {k_fixed}\nMSTAB = {data.mstab}\nJSTAB = {data.jstab}\n"
                  f"SAFE1 = {data.safe1!r}\nSAFE2 = {data.safe2!r}\nSAFE3 = {data.safe3!r}\n"
                  f"FAC1 = {data.fac1!r}\nFAC2 = {data.fac2!r}\nFAC3 = {data.fac3!r}\n"
                  f"FAC4 = {data.fac4!r}\nUROUND = 2.3e-16\nHINIT_ORDER = {data.hinit_order}\n")
        comma = "," if ctx.n == 1 else ""
        shift = ", ".join(f"y[{i}] + h * v[{i}]" for i in range(ctx.n))
        scale = ", ".join(f"a * v[{i}]" for i in range(ctx.n))
        src = (consts + f"\n@njit(cache=True, inline='always')\ndef to_tuple_shift(y, h, v):\n"
               f"    return ({shift}{comma})\n"
               f"\n@njit(cache=True, inline='always')\ndef scaled(a, v):\n"
               f"    return ({scale}{comma})\n"
               + template(extrapolation.gragg_column, inline=True)
               + template(extrapolation.neville, inline=True)
               + "".join(template(getattr(extrapolation, name), inline=name == "solution")
                         for name in ("make_ws", "fixed_increment", "step", "step_sum",
                                      "solution")))
        if kmax:
            loop = adaptive.integrate_adaptive
            src += ("\nFSAL = False\n"
                    + template(adaptive.initial_step, {"IORD": "HINIT_ORDER"}, inline=True)
                    + template(adaptive.first_step, inline=True)
                    + "".join(template(getattr(extrapolation, name), inline=name in INLINE)
                              for name in ("column", "adaptive_ws", "controller_init",
                                           "controller_state", "controller_clip",
                                           "controller_prepare", "attempt", "attempt_outcome",
                                           "controller_accept", "controller_reject",
                                           "partial_adaptive"))
                    + variant(loop, "integrate_adaptive")
                    + grid_functions("adaptive", "partial_adaptive")
                    + variant(loop, "adaptive_grid", "GRID", "GRIDDED",
                              rename={"grid_rows": "grid_rows_adaptive"}))
            if ctx.problem is not None and ctx.problem.sections:
                src += variant(loop, "adaptive_section", "SECTION")
        return src
    return generate


def _params():
    only = ("adaptive", True)
    return (
        Param("adaptive", True, "adaptive order and step (else fixed step h, k columns)",
              kind="bool"),
        Param("h", 0.01, "step size (fixed-step mode)", low=0.0, low_open=True,
              only_if=("adaptive", False)),
        Param("k", 4, "columns of the tableau (fixed-step mode): order 2k", kind="int", low=1,
              high=KMAX_LIMIT, only_if=("adaptive", False)),
        Param("kmax", 9, "maximal number of columns (ODEX's KM); orders up to 2 kmax",
              kind="int", low=3, high=KMAX_LIMIT, only_if=only, show_default=False),
    ) + adaptive_params(1e-9)


odex = Method(id="odex", family="extrapolation", order=8,
              reference="HNW I §II.9; Hairer's ODEX (beyond the seeds)",
              doc="GBS extrapolation (harmonic sequence), adaptive order and step as in ODEX; "
                  "fixed mode: k columns, order 2k (declared order: the default k=4)",
              generate=_generate(ODEX), data=ODEX, params=_params(), summation="plain")
