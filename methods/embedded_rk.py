"""Embedded Runge-Kutta pairs: fixed step, or adaptive with Hairer's step-size control.

Each pair is data: a tableau (the propagated solution), error weights e = b - b̂ over the stages
(and over f(y1) when the last stage is f(y1), "first same as last"), the controller constants of
the code it follows and, for DOPRI5 and DOP853, the continuous extension (methods/dense_output.py).
One generator writes the cell's ``step`` (fixed step: the propagated solution) or ``attempt``
(adaptive: also the scaled rms error and the verdict) and ``attempt_stages`` (the same lines, also
returning the stages, for dense output); under ``sum=compensated`` they add the increment
h Σ b_i k_i to y with the carried rounding error (methods/summation.py). The adaptive loop of
methods/assembly/templates/adaptive.py drives them with Hairer's controller (methods/assembly/templates/pair.py).
"""
from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction as Fr

import gnibench.methods.dop853_coefficients as dop853_data
from gnibench.methods import order_conditions as oc
from gnibench.methods.assembly.steps.pair import write_pair
from gnibench.methods.base import Method, adaptive_params
from gnibench.methods.dense_output import DenseOutput
from gnibench.methods.tableau import Tableau, require, tableau, verdict
from gnibench.suite.foundation.params import Param


@dataclass(frozen=True)
class Pair:
    """An embedded pair with the constants of its step-size controller (HNW I, §II.4)."""

    tab: Tableau
    e: tuple                    # error weights over the stages (incl. f(y1) if fsal)
    iord: int                   # order used by the initial-step heuristic
    expo: float                 # err exponent: 1/(q+1) - 0.75 beta (DOPRI5), 1/8 (DOP853)
    beta: float = 0.0           # PI stabilisation (DOPRI5: 0.04)
    safe: float = 0.9
    fac1: float = 0.2           # new h / old h >= fac1
    fac2: float = 10.0          # new h / old h <= fac2
    e3: tuple | None = None     # DOP853's 3rd-order weights (its combined estimate)
    dense: DenseOutput | None = None   # continuous extension (Hairer's CONTD5 / CONTD8)
    embedded_order: int = 0     # order of b̂ = b - e, checked when given
    tol: float = 0              # tolerance of that check (decimal or double data)

    def __post_init__(self):
        if abs(sum(self.e)) > 1e-14:
            raise ValueError("error weights must sum to 0 (b and b̂ both sum to 1)")
        if self.embedded_order:
            bhat = [x - oc.number(e) for x, e in zip(self.tab.b, self.e)]
            require(verdict("tableau", self.embedded_order, self.tol, self.tab.a, bhat, None),
                    f"embedded weights b - e of order {self.embedded_order}")
        if self.fsal and len(self.e) != self.tab.stages:
            raise ValueError("error weights must cover every stage")
        if self.dense is not None:
            self.dense.check(self.tab)

    @property
    def fsal(self) -> bool:
        """The last stage is f(y1): its row of A is b and its c is 1."""
        s = self.tab.stages
        return self.tab.c[-1] == 1 and all(self.tab.a[s - 1][j] == self.tab.b[j] for j in range(s))

    @property
    def lazy_last(self) -> bool:
        """f(y1) is a stage the error estimate does not use (DOP853): evaluate it only once the
        step is accepted, as Hairer's code does (11 evaluations per attempt, + 1 per accepted
        step), instead of in every attempt (DOPRI5's 7th stage enters its estimate)."""
        return self.fsal and self.e[-1] == 0 and (self.e3 is None or self.e3[-1] == 0)


def _fr(x):
    return Fr(x) if isinstance(x, str) else Fr(float(x))


# Dormand-Prince 5(4), as in Hairer's DOPRI5 (HNW I, Table II.5.2); stage 7 is f(y1).
DOPRI5 = Pair(
    tab=tableau(
        [[0] * 7, ["1/5"] + [0] * 6, ["3/40", "9/40"] + [0] * 5,
         ["44/45", "-56/15", "32/9"] + [0] * 4,
         ["19372/6561", "-25360/2187", "64448/6561", "-212/729", 0, 0, 0],
         ["9017/3168", "-355/33", "46732/5247", "49/176", "-5103/18656", 0, 0],
         ["35/384", 0, "500/1113", "125/192", "-2187/6784", "11/84", 0]],
        ["35/384", 0, "500/1113", "125/192", "-2187/6784", "11/84", 0],
        [0, "1/5", "3/10", "4/5", "8/9", 1, 1], order=5),
    e=tuple(Fr(x) for x in ("71/57600", "0", "-71/16695", "71/1920", "-17253/339200", "22/525",
                            "-1/40")),
    iord=5, expo=0.2 - 0.04 * 0.75, beta=0.04, fac1=0.2, fac2=10.0, embedded_order=4,
    # Hairer's DOPRI5 (CONTD5, its D1..D7 over the stages k1..k6, f(y1)); HNW I §II.6
    dense=DenseOutput(order=4, d=(tuple(Fr(x) for x in (
        "-12715105075/11282082432", "0", "87487479700/32700410799", "-10690763975/1880347072",
        "701980252875/199316789632", "-1453857185/822651844", "69997945/29380423")),),
        reference="Hairer's DOPRI5, CONTD5; HNW I §II.6"))

# Runge-Kutta-Fehlberg 4(5), propagating the 4th-order solution ([B] §4.1 "RKF method").
_RKF_B4 = ["25/216", 0, "1408/2565", "2197/4104", "-1/5", 0]
_RKF_B5 = ["16/135", 0, "6656/12825", "28561/56430", "-9/50", "2/55"]
RKF45 = Pair(
    tab=tableau(
        [[0] * 6, ["1/4"] + [0] * 5, ["3/32", "9/32"] + [0] * 4,
         ["1932/2197", "-7200/2197", "7296/2197"] + [0] * 3,
         ["439/216", -8, "3680/513", "-845/4104", 0, 0],
         ["-8/27", 2, "-3544/2565", "1859/4104", "-11/40", 0]],
        _RKF_B4, [0, "1/4", "3/8", "12/13", 1, "1/2"], order=4),
    e=tuple(Fr(a) - Fr(b) for a, b in zip(_RKF_B4, _RKF_B5)), iord=5, expo=0.2, embedded_order=5)

# Kutta-Merson 4("5"): estimate (h/30)(2k1 - 9k3 + 8k4 - k5)  ([B] §6 and §8 use Merson's method).
MERSON = Pair(
    tab=tableau(
        [[0] * 5, ["1/3"] + [0] * 4, ["1/6", "1/6", 0, 0, 0], ["1/8", 0, "3/8", 0, 0],
         ["1/2", 0, "-3/2", 2, 0]],
        ["1/6", 0, 0, "2/3", "1/6"], [0, "1/3", "1/3", "1/2", 1], order=4),
    e=tuple(Fr(x, 30) for x in (2, 0, -9, 8, -1)), iord=5, expo=0.2, embedded_order=3)

# Dormand-Prince 8(5,3), as in Hairer's DOP853: 12 stages, then f(y1) as a 13th (FSAL) stage.
_A = [[_fr(dop853_data.A[i, j]) for j in range(13)] for i in range(12)]
_A.append([_fr(x) for x in dop853_data.B] + [Fr(0)])
DOP853 = Pair(
    tab=Tableau(tuple(tuple(r) for r in _A), tuple(_A[12]),
                tuple(_fr(x) for x in dop853_data.C[:13]), order=8, tol=1e-14),
    e=tuple(_fr(x) for x in dop853_data.E5), e3=tuple(_fr(x) for x in dop853_data.E3),
    iord=8, expo=1.0 / 8.0, beta=0.0, fac1=0.333, fac2=6.0, embedded_order=5, tol=1e-14,
    # Hairer's DOP853 (CONTD8): 3 extra stages over the 12, f(y1) and each other; 4 rows of D
    dense=DenseOutput(order=7,
                      d=tuple(tuple(float(x) for x in row) for row in dop853_data.D),
                      extra_a=tuple(tuple(float(x) for x in dop853_data.A[i, :i]) for i in range(13, 16)),
                      extra_c=tuple(float(x) for x in dop853_data.C[13:16]),
                      reference="Hairer's DOP853, CONTD8; HNW I §II.6", tol=1e-11))


DT_OUT = Param("dt_out", 0.0, "output on the grid k dt_out by dense output, the steps unchanged "
               "(0: a sample every `every` accepted steps)", low=0.0, only_if=("adaptive", True),
               show_default=False)


def _params(adaptive_default: bool, rtol: float, dense: bool):
    return (
        Param("adaptive", adaptive_default, "adaptive step size (else fixed step h)", kind="bool"),
        Param("h", 0.01, "step size (fixed-step mode)", low=0.0, low_open=True,
              only_if=("adaptive", False)),
    ) + adaptive_params(rtol) + ((DT_OUT,) if dense else ())


def embedded(id, pair, order, reference, doc, adaptive_default=True, rtol=1e-6,
             summation="plain"):
    """An embedded pair; ``summation``: the default of its option ``sum`` (methods/summation.py)."""
    return Method(id=id, family="embedded-rk", order=order, reference=reference, doc=doc,
                  generate=write_pair(pair), data=pair,
                  params=_params(adaptive_default, rtol, pair.dense is not None),
                  summation=summation)


merson = embedded("merson", MERSON, 4, "[B] §6, §8", "Kutta-Merson 4(5); fixed step by default",
                  adaptive_default=False)
rkf45 = embedded("rkf45", RKF45, 4, "[B] §4.1, §7", "Runge-Kutta-Fehlberg 4(5), adaptive")
dopri5 = embedded("dopri5", DOPRI5, 5, "[B] §5; Hairer's DOPRI5", "Dormand-Prince 5(4), adaptive")
dop853 = embedded("dop853", DOP853, 8, "Hairer's DOP853 (beyond the seeds)",
                  "Dormand-Prince 8(5,3), adaptive")
