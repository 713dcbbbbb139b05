"""Declared properties of a user method, checked like its order (a false one is refused, naming
the key and the failing condition):

* ``symplectic`` of a Runge-Kutta tableau: b_i a_ij + b_j a_ji − b_i b_j = 0 for all i, j
  ([HLW] VI.4.1, Theorem 4.3); of a partitioned one: b_i = b̂_i and
  b_i â_ij + b̂_j a_ji − b_i b̂_j = 0 ([HLW] VI.4.2, Theorem 4.6); of a composition: a
  symplectic basis (a composition of symplectic maps is symplectic, [HLW] VI.2).
* ``symmetric`` of a tableau: a_σ(i)σ(j) + a_ij = b_j for the stage permutation σ that reverses
  the stages, or maps c_i to 1 − c_i ([HLW] V.2.2, Theorem 2.3, (2.4)); of a partitioned one,
  both tableaus with one σ; of a composition: a symmetric basis and γ_i = γ_{s+1−i}
  ([HLW] V.3.1).

Entries are Fractions (exact, or irrational ones to 50 digits); ``tol`` is the absolute
tolerance (0 for exact rationals, 1e-40 for 50-digit entries, more for printed decimals).
"""
from __future__ import annotations

from fractions import Fraction


def symplectic_failure(u, v=None, tol=0) -> str:
    """Why the tableau ``u`` = (A, b) (with ``v`` = (Â, b̂): the partitioned pair) is not
    symplectic, or ""."""
    a, b = u
    ah, bh = v if v is not None else u
    s = len(b)
    for i in range(s):
        if abs(b[i] - bh[i]) > tol:
            return f"b_{i + 1} = {b[i]} ≠ b̂_{i + 1} = {bh[i]} ([HLW] VI.4.2, Theorem 4.6)"
    for i in range(s):
        for j in range(s):
            m = b[i] * ah[i][j] + bh[j] * a[j][i] - b[i] * bh[j]
            if abs(m) > tol:
                hat = "̂" if v is not None else ""
                return (f"b_{i + 1} a{hat}_{i + 1}{j + 1} + b{hat}_{j + 1} a_{j + 1}{i + 1} − "
                        f"b_{i + 1} b{hat}_{j + 1} = {_show(m)} ≠ 0 ([HLW] VI.4, Theorem "
                        f"{'4.6' if v is not None else '4.3'})")
    return ""


def symmetric_failure(tableaus, c, tol=0) -> str:
    """Why the tableaus (each (A, b), one set of stages with nodes ``c``) are not symmetric in
    the sense of [HLW] V.2.2 (2.4), or ""."""
    s = len(c)
    perms = [list(range(s - 1, -1, -1))]
    match = [[j for j in range(s) if abs(c[j] - (1 - c[i])) <= tol] for i in range(s)]
    if all(len(m) == 1 for m in match) and len({m[0] for m in match}) == s:
        perms.append([m[0] for m in match])
    first = ""
    for sigma in perms:
        why = ""
        for a, b in tableaus:
            for i in range(s):
                for j in range(s):
                    d = a[sigma[i]][sigma[j]] + a[i][j] - b[j]
                    if not why and abs(d) > tol:
                        why = (f"a_{sigma[i] + 1}{sigma[j] + 1} + a_{i + 1}{j + 1} − b_{j + 1} = "
                               f"{_show(d)} ≠ 0 ([HLW] V.2.2, (2.4))")
        if not why:
            return ""
        first = first or why
    return first


def _show(x) -> str:
    if isinstance(x, Fraction) and x.denominator < 10 ** 12:
        return str(x)
    return f"{float(x):.3g}"


def tolerance(rational: bool, rtol: float | None, entries) -> Fraction:
    """The absolute tolerance of the conditions above: 0 for exact rationals, 1e-40 for entries
    known to 50 digits, ``rtol`` (printed decimals) times the square of the largest entry."""
    if rtol is not None:
        top = max((abs(x) for x in entries), default=Fraction(1))
        return Fraction(rtol) * max(Fraction(1), top) ** 2
    return Fraction(0) if rational else Fraction(1, 10 ** 40)


def check_declared(e, info: dict, u, v, c, tol) -> None:
    """Refuse a declared ``symplectic`` or ``symmetric`` that the tableau ``u`` (and ``v``, a
    partitioned pair) does not have (``e``: the entry, for the error)."""
    checks = (("symplectic", lambda: symplectic_failure(u, v, tol)),
              ("symmetric", lambda: symmetric_failure([u] if v is None else [u, v], c, tol)))
    for key, failure in checks:
        why = failure() if info[key] else ""
        if why:
            raise e.error(key, f"declared true, but the tableau is not {key}: {why}")
