"""Coefficients printed as decimals: a coefficient written to d >= 10 significant digits (Yoshida's
0.784513610477560) is a rounding of the true one, so the order conditions of a user tableau or
composition hold only to about 10^(2-d); they are then checked in doubles to that relative
tolerance (docs: reference, "User definitions"), exact ones exactly (:mod:`.methods`).
"""
from __future__ import annotations

import re
from fractions import Fraction

PRINTED = 10          # decimals of at least this many significant digits are printed roundings
_DECIMAL = re.compile(r"(?<![\w.])(\d*\.\d+|\d+\.?\d*)(?:[eE][+-]?\d+)?")


def printed_digits(value) -> int:
    """The most significant digits among the decimal numbers written in ``value`` (a number, a
    text, or lists and tables of them): 15 for Yoshida's 0.784513610477560. A coefficient printed
    to d >= 10 digits is a rounding of the true one, so its order conditions hold only to about
    10^(2-d) (relative); shorter decimals (0.5, 0.125) are taken as exact."""
    if isinstance(value, bool):
        return 0
    if isinstance(value, float):
        value = repr(value)
    if isinstance(value, (list, tuple)):
        return max((printed_digits(v) for v in value), default=0)
    if isinstance(value, dict):
        return max((printed_digits(v) for v in value.values()), default=0)
    if not isinstance(value, str):
        return 0
    best = 0
    for m in _DECIMAL.finditer(value):
        mantissa = m.group(1)
        if "." not in mantissa and "e" not in m.group(0).lower():
            continue                                   # an integer: exact
        best = max(best, len(mantissa.replace(".", "").lstrip("0")))
    return best


def printed_rtol(digits: int) -> float | None:
    """The relative tolerance of the order conditions for coefficients printed to ``digits``
    significant digits (None: exact)."""
    return max(10.0 ** (2 - digits), 1e-13) if digits >= PRINTED else None


def _float_rk_check(a, b, c, order: int, rtol: float) -> list:
    """Failing order conditions of an RK tableau over rooted trees in double precision: a
    condition holds when |Σ b Φ − 1/γ| <= rtol (Σ |b| |Φ| + 1/γ), Φ of (|A|, |b|) in the scale
    (the bound of a relative perturbation of every coefficient; as
    :func:`gnibench.methods.prk_conditions.check` for floats)."""
    import numpy as np
    from gnibench.methods import order_conditions as oc

    A, B = np.array([[float(x) for x in row] for row in a]), np.array([float(x) for x in b])
    out = []
    if c is not None:
        for i, row in enumerate(A):
            if abs(row.sum() - float(c[i])) > rtol * (np.abs(row).sum() + abs(float(c[i]))):
                out.append(oc.Failure(0, "", f"Σ_j a_{i + 1}j (row {i + 1})", float(row.sum()),
                                      c[i]))
    phi, mag, a_phi, a_mag = {(): np.ones(len(B))}, {(): np.ones(len(B))}, {}, {}
    for k, level in enumerate(oc.trees(order), 1):
        for tree in level:
            if tree:
                vec, m = np.ones(len(B)), np.ones(len(B))
                for child in tree:
                    if child not in a_phi:
                        a_phi[child], a_mag[child] = A @ phi[child], np.abs(A) @ mag[child]
                    vec, m = vec * a_phi[child], m * a_mag[child]
                phi[tree], mag[tree] = vec, m
            got, want = float(B @ phi[tree]), 1.0 / oc.density(tree)
            if abs(got - want) > rtol * (float(np.abs(B) @ mag[tree]) + want):
                out.append(oc.Failure(k, oc.bracket(tree), oc.expression(tree), got,
                                      Fraction(1, oc.density(tree))))
    return out
