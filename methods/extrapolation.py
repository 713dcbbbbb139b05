"""Gragg-Bulirsch-Stoer extrapolation with adaptive order and step, as in Hairer's ODEX.

The method is data: the step-number sequence n_j and ODEX's controller constants (HNW I, §II.9).
Column j of the tableau is Gragg's midpoint rule with n_j substeps and the smoothing step
(HNW (9.13)), extrapolated by Aitken-Neville in h² (HNW (9.10)); with the harmonic sequence
n_j = 2j the value T_kk has order 2k (HNW Theorem II.9.1). Adaptive mode (the default) runs
ODEX's order and step-size control (methods/assembly/templates/odex.py); ``adaptive=false`` takes
fixed steps h with k columns, order 2k. ``sum=compensated`` adds the extrapolated increment to y
with the carried rounding error (methods/summation.py).
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass

from gnibench.methods.assembly.steps.odex import write_odex
from gnibench.methods.base import Method, adaptive_params
from gnibench.suite.foundation.params import Param


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
ODEX = Extrapolation(sequence=harmonic(KMAX_LIMIT))


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
              generate=write_odex(ODEX), data=ODEX, params=_params(), summation="plain")
