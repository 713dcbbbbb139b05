"""Round-off control: compensated summation of the increments, the method option ``sum``.

A one-step method advances y_{n+1} = y_n + Δ_n with the increment Δ_n = h Σ b_i k_i (explicit and
embedded Runge-Kutta), Σ d_j Z_j (implicit Runge-Kutta), the extrapolated increment T_kk - y_n
(odex), or one increment per block and stage (partitioned methods and their compositions). Added in
floating point, each addition rounds y_{n+1} by up to half an ulp of y; over n steps these
roundings add up, and where they have a sign bias (a slowly varying component, a step size that
repeats) the error grows like n instead of the √n of a random walk.

With ``sum=compensated`` the increments are formed first and then added with the rounding error
carried to the next step: [HLW] VIII.5 (GNI 2nd ed., "Reducing rounding errors"), Algorithm 5.1
(compensated summation, after Kahan 1965): with e the carried error,

    x = e + Δ_n,   y_{n+1} = y_n + x,   e = (y_n - y_{n+1}) + x,

where the last line, the error of the addition, is computed here by Knuth's TwoSum
(s = a + b, b' = s - a, err = (a - (s - b')) + (b - b')), which is exact whatever the magnitudes of
a and b (Neumaier's improvement of Kahan's summation, Kahan-Babuška; Neumaier 1974), where
HLW's three-operation form needs |y_n| >= |x| (a component that crosses zero breaks it). The state
used everywhere (fields, error estimates, samples) is the rounded y_n; e (|e| <= ulp(y_n)/2) lives
in row ``ROW_CARRY`` of ``y_io`` between calls (methods/assembly/templates/slots.py), so a run paused and
resumed anywhere gives the same bits. The time t of the adaptive drivers is summed the same way
(slot ``ST_T_CARRY``), and their last step is (t_end - t_n) - e_t, so the steps add up to t_end.
Partial steps of a time grid and the located section points start from y_n + e_n. A step modifier
(``+projection``) or a problem's identification map (``post_step``) that moves the point drops
the carry (the new point is not y_{n+1} + e). ``sum=plain`` (the default of the seeds' methods)
generates exactly the code it did before this option existed: same operations, same bits. The
carries' code is written into every kernel module (methods/assembly/cell.py ``carry_source``).
"""
from __future__ import annotations

from gnibench.suite.foundation.params import Param

CHOICES = ("plain", "compensated")


def sum_param(default: str = "plain") -> Param:
    """The option ``sum`` with the method's own default (``Method.summation``)."""
    if default not in CHOICES:
        raise ValueError(f"summation default {default!r}; allowed: {', '.join(CHOICES)}")
    return Param("sum", default, "summation of the increments y_n+1 = y_n + Δ and of t: plain, or "
                 "compensated (Kahan-Babuška, [HLW] VIII.5) against the round-off of long runs",
                 kind="str", choices=CHOICES, show_default=False)


def compensated(values: dict) -> bool:
    """True when a method's values ask for compensated summation."""
    return values.get("sum") == "compensated"
