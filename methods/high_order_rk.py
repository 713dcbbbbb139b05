"""High-order embedded pairs as data: Verner's 6(5), 7(6), 8(7), 9(8) with interpolants, Feagin's 10(8).

The coefficients live in methods/verner_coefficients.py and methods/feagin_coefficients.py, exactly
as published (rationals, Q(√6), decimals converted digit for digit); here they become
:class:`~gnibench.methods.embedded_rk.Pair` records, validated by the order conditions in exact
arithmetic on construction (methods/order_conditions.py): b at the pair's order p, b̂ = b - e at
its embedded order, the interpolant at its order as a polynomial identity in θ. They run through
the same generator and adaptive driver as DOPRI5 and DOP853 (methods/embedded_rk.py,
methods/assembly/templates/adaptive.py), with dense output by polynomial weights (methods/dense_output.py).

Controller (choice, as for DOP853 in Hairer's code): the estimate of a p(p-1) pair is O(h^p), so
err^(1/p) drives the step (Feagin 10(8): O(h^9), 1/9); no PI term (beta = 0), safety 0.9, step
ratio within [1/6, 3].

Measured (tests/methods/test_order_conditions.py, no cache): every condition of b and b̂ holds exactly for
Verner's pairs; the interpolants of Vern6 exactly (order 6), Vern8 and Vern9 within 1e-30 (their
extra stages and weights are 40-digit decimals). Vern7's published order-7 interpolant (six extra
stages, as in OrdinaryDiffEq.jl's Vern7 and Geant4's VernerRK67, both from Verner's file
RKV76.IIa.Efficient.00001675585.081206) satisfies the order-6 conditions to 1e-30 but misses 72
of the 719 order-7 conditions by up to 1.3e-4 (all on trees of height >= 3): we declare it order 6.
Feagin's 10(8): order 10 and 8 within 1e-60 (60+-digit decimals).
"""
from __future__ import annotations

from fractions import Fraction

from gnibench.methods import feagin_coefficients as feagin_data
from gnibench.methods import order_conditions as oc
from gnibench.methods import verner_coefficients as verner_data
from gnibench.methods.dense_output import DenseOutput
from gnibench.methods.embedded_rk import Pair, embedded
from gnibench.methods.tableau import Tableau


def _table(text: str) -> dict[tuple[int, ...], object]:
    """'i j value' (or 'j value', 'j p value') lines as {(i, j): exact number}, 0-based indices
    for stages, powers as given."""
    out = {}
    for line in text.split("\n"):
        if line.strip():
            *idx, value = line.split()
            key = tuple(int(i) for i in idx)
            out[key] = oc.number(value)
    return out


def _matrix(a: dict, size: int) -> list[list]:
    rows = [[Fraction(0)] * size for _ in range(size)]
    for (i, j), x in a.items():
        if i <= size:
            rows[i - 1][j - 1] = x
    return rows


def _row_sum(row):
    return sum(row, Fraction(0))


def verner_pair(data: dict, order: int, dense_order: int, dense_tol: float) -> Pair:
    """A Verner pair from its table: the first ``stages`` rows of A, b, e = b - b̂; the rest of A
    are the interpolant's extra stages; r its weights (θ^1 ... θ^q)."""
    s = data["stages"]
    a_all, r = _table(data["a"]), _table(data["r"])
    total = max(i for i, _ in a_all) if a_all else s
    rows = _matrix(a_all, total)
    b = [Fraction(0)] * s
    for (j,), x in _table(data["b"]).items():
        b[j - 1] = x
    e = [Fraction(0)] * s
    for (j,), x in _table(data["e"]).items():
        e[j - 1] = x
    a = tuple(tuple(row[:s]) for row in rows[:s])
    tab = Tableau(a, tuple(b), tuple(_row_sum(row) for row in a), order, round_to_sums=True)
    q = max(p for _, p in r)
    b_theta = tuple(tuple(r.get((j, p), Fraction(0)) for p in range(1, q + 1))
                    for j in range(1, total + 1))
    dense = DenseOutput(order=dense_order, b_theta=b_theta,
                        extra_a=tuple(tuple(rows[i][:i]) for i in range(s, total)),
                        extra_c=tuple(_row_sum(rows[i]) for i in range(s, total)),
                        reference=f"Verner (2010), interpolant of order {dense_order}", tol=dense_tol)
    return Pair(tab=tab, e=tuple(e), iord=order, expo=1.0 / order, beta=0.0, fac1=0.333, fac2=6.0,
                dense=dense, embedded_order=order - 1)


def feagin_pair() -> Pair:
    """Feagin's 10(8): 17 stages; the estimate h (k_2 - k_16) / 360 (Feagin 2007)."""
    data = feagin_data.FEAGIN10
    s = data["stages"]
    a = _matrix(_table(data["a"]), s)
    b = [Fraction(0)] * s
    for (j,), x in _table(data["b"]).items():
        b[j - 1] = x
    c = [Fraction(0)] * s
    for (j,), x in _table(data["c"]).items():
        c[j - 1] = x
    e = [Fraction(0)] * s
    e[1], e[15] = Fraction(1, 360), Fraction(-1, 360)
    tab = Tableau(tuple(tuple(r) for r in a), tuple(b), tuple(c), 10, tol=1e-60, round_to_sums=True)
    return Pair(tab=tab, e=tuple(e), iord=10, expo=1.0 / 9.0, beta=0.0, fac1=0.333, fac2=6.0,
                embedded_order=8, tol=1e-60)


VERN6 = verner_pair(verner_data.VERN6, 6, 6, 0)
VERN7 = verner_pair(verner_data.VERN7, 7, 6, 1e-30)
VERN8 = verner_pair(verner_data.VERN8, 8, 8, 1e-30)
VERN9 = verner_pair(verner_data.VERN9, 9, 9, 1e-30)
FEAGIN10 = feagin_pair()

_REF = "Verner, Numer. Algorithms 53 (2010) 383-396 (beyond the seeds)"
vern6 = embedded("vern6", VERN6, 6, _REF, "Verner's efficient 6(5) pair, interpolant of order 6",
                 rtol=1e-8, summation="compensated")
vern7 = embedded("vern7", VERN7, 7, _REF, "Verner's efficient 7(6) pair, interpolant of order 6 "
                 "(the published order-7 one misses 72 order-7 conditions)", rtol=1e-8,
                 summation="compensated")
vern8 = embedded("vern8", VERN8, 8, _REF, "Verner's efficient 8(7) pair, interpolant of order 8",
                 rtol=1e-10, summation="compensated")
vern9 = embedded("vern9", VERN9, 9, _REF, "Verner's efficient 9(8) pair, interpolant of order 9",
                 rtol=1e-10, summation="compensated")
feagin10 = embedded("feagin10", FEAGIN10, 10, "Feagin (2007), IAENG conf. (beyond the seeds)",
                    "Feagin's 10(8) pair (no dense output: time grid by partial steps)", rtol=1e-12,
                    summation="compensated")
