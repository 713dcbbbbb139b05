"""Embedded Runge-Kutta pairs: fixed step, or adaptive with Hairer's step-size control.

Each pair is data: a tableau (the propagated solution), error weights e = b - b̂ over the stages
(and over f(y1) when the last stage is f(y1), "first same as last"), the controller constants of
the code it follows and, for DOPRI5 and DOP853, the continuous extension (methods/dense_output.py).
One generator writes the cell's ``step`` (fixed step: the propagated solution) or ``attempt``
(adaptive: also the scaled rms error and the verdict) and ``attempt_stages`` (the same lines, also
returning the stages, for dense output); under ``sum=compensated`` they add the increment
h Σ b_i k_i to y with the carried rounding error (methods/summation.py). The adaptive loop of
methods/kernels/adaptive.py drives them with Hairer's controller (methods/kernels/pair.py).
"""
from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction as Fr

import gnibench.methods.dop853_coefficients as dop853_data
from gnibench.methods import order_conditions as oc
from gnibench.methods.base import Method, adaptive_params
from gnibench.methods.dense_output import DenseOutput, generate_dense
from gnibench.methods.events import (
    dense_grid_rows,
    dense_section_rows,
    grid_functions,
    root_functions,
    variant,
)
from gnibench.methods.explicit_rk import combination, generate_erk, increment, stage_lines
from gnibench.methods.kernels import adaptive
from gnibench.methods.kernels import pair as pair_kernel
from gnibench.methods.summation import compensated
from gnibench.methods.tableau import Tableau, lit, require, tableau, verdict
from gnibench.suite.foundation.params import Param
from gnibench.suite.foundation.templates import template


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


def _error_lines(pair: Pair, n: int) -> list[str]:
    """Scaled rms error of the step; DOP853 combines its 5th- and 3rd-order estimates."""
    def comb(w, i):
        return " + ".join(f"{lit(c)} * k{j}[{i}]" for j, c in enumerate(w) if c != 0)

    lines = ["    acc = 0.0", "    acc3 = 0.0"]
    for i in range(n):
        lines.append(f"    sk = atol + rtol * max(abs(y[{i}]), abs(y1[{i}]))")
        if pair.e3 is None:
            lines.append(f"    acc += (h * ({comb(pair.e, i)}) / sk) ** 2")
        else:
            lines.append(f"    acc += (({comb(pair.e, i)}) / sk) ** 2")
            lines.append(f"    acc3 += (({comb(pair.e3, i)}) / sk) ** 2")
    if pair.e3 is None:
        lines.append(f"    err = math.sqrt(acc / {n})")
    else:  # DOP853: err = |h| err5^2 / sqrt(n (err5^2 + 0.01 err3^2))
        lines += ["    deno = acc + 0.01 * acc3",
                  "    if deno <= 0.0:", "        deno = 1.0",
                  f"    err = abs(h) * acc / math.sqrt(deno * {n})"]
    return lines


def _pair_functions() -> str:
    """The pair's parts of the adaptive loop (methods/kernels/pair.py); the small ones inlined."""
    names = ("adaptive_ws", "controller_init", "controller_state", "controller_clip",
             "controller_prepare", "attempt_outcome", "controller_accept", "controller_reject",
             "dense_coeffs", "partial_adaptive")
    small = ("adaptive_ws", "controller", "attempt_outcome")
    return "".join(template(getattr(pair_kernel, name), inline=name.startswith(small))
                   for name in names)


def generate_adaptive(data: Pair):
    def generate(ctx) -> str:
        n, s, tab = ctx.n, data.tab.stages, data.tab
        count = s - 1 if data.fsal else s
        stages = stage_lines(tab, count, n, first="k0")
        fsal = data.fsal and not data.lazy_last
        knew = f"k{s - 1}" if fsal else "k0"  # else the loop evaluates f(y1) once accepted
        if compensated(ctx.values):     # the increment h Σ b_i k_i added with the carried error
            inc = increment(tab.doubles[1], n)
            new_y, carry = [f"    y1, e1 = carry_add(y, e, {inc})"], "e1"
        else:
            new_y, carry = [f"    y1 = {combination(tab.doubles[1], n)}"], "e"
        lines = (stages + new_y + ([f"    k{s - 1} = f(y1, par)"] if fsal else [])
                 + _error_lines(data, n))
        head = "(y, e, k0, h, par, ws, rtol, atol):"
        # attempt_stages: the very same lines (hence the same y1 and err, bit for bit), also
        # returning the stages for the continuous extension
        ks = ", ".join(f"k{j}" for j in range(count)) + ("," if count == 1 else "")
        body = (["\n@njit(cache=True)\ndef attempt" + head] + lines
                + [f"    return y1, {carry}, err, {knew}"]
                + ["\n@njit(cache=True)\ndef attempt_stages" + head] + lines
                + [f"    return y1, {carry}, err, {knew}, ({ks})"])
        sections = bool(ctx.problem is not None and ctx.problem.sections)
        drive = adaptive.integrate_adaptive
        src = (variant(drive, "integrate_adaptive") + grid_functions("adaptive", "partial_adaptive")
               + variant(drive, "adaptive_grid", "GRID", "GRIDDED",
                         rename={"grid_rows": "grid_rows_adaptive"}))
        if sections:
            src += variant(drive, "adaptive_section", "SECTION")
        dense_nfev = 0.0
        if data.dense is not None:            # integrate_dense and what it calls
            dense_src = generate_dense(data.dense, tab, count, n)
            dense_nfev = float(data.dense.new_stages(tab))
            src += (dense_src + root_functions(n, sections) + dense_grid_rows()
                    + variant(drive, "integrate_dense", "DENSE_OUTPUT", "GRIDDED", "WITH_STAGES",
                              rename={"grid_rows": "grid_rows_dense"}))
            if sections:
                src += (dense_section_rows()
                        + variant(drive, "adaptive_section_dense", "SECTION", "SECTION_DENSE",
                                  "WITH_STAGES", rename={"section_rows": "section_rows_dense"}))
        comma = "," if n == 1 else ""
        shift = ", ".join(f"y[{i}] + h * v[{i}]" for i in range(n))
        consts = (f"\nFSAL = {fsal}\nSTAGES_NEW = {float(count - 1 + fsal)!r}\n"
                  f"IORD = {data.iord}\nEXPO = {data.expo!r}\nBETA = {data.beta!r}\n"
                  f"SAFE = {data.safe!r}\nFAC1 = {data.fac1!r}\nFAC2 = {data.fac2!r}\n"
                  f"DENSE_NFEV = {dense_nfev!r}\n"
                  f"\n@njit(cache=True, inline='always')\ndef to_tuple_shift(y, h, v):\n"
                  f"    return ({shift}{comma})\n")
        return (consts + "\n".join(body) + "\n"
                + template(adaptive.initial_step, inline=True)
                + template(adaptive.first_step, inline=True)
                + _pair_functions() + src)
    return generate


def _generate(pair: Pair):
    fixed, adaptive_ = generate_erk(pair.tab), generate_adaptive(pair)

    def generate(ctx) -> str:
        src = fixed(ctx)
        if ctx.values.get("adaptive"):
            src += adaptive_(ctx)
        return src
    return generate


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
                  generate=_generate(pair), data=pair,
                  params=_params(adaptive_default, rtol, pair.dense is not None),
                  summation=summation)


merson = embedded("merson", MERSON, 4, "[B] §6, §8", "Kutta-Merson 4(5); fixed step by default",
                  adaptive_default=False)
rkf45 = embedded("rkf45", RKF45, 4, "[B] §4.1, §7", "Runge-Kutta-Fehlberg 4(5), adaptive")
dopri5 = embedded("dopri5", DOPRI5, 5, "[B] §5; Hairer's DOPRI5", "Dormand-Prince 5(4), adaptive")
dop853 = embedded("dop853", DOP853, 8, "Hairer's DOP853 (beyond the seeds)",
                  "Dormand-Prince 8(5,3), adaptive")
