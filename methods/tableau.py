"""Butcher tableaus as validated, exact data ([HLW] II.1; diffrax-style checks in __post_init__)."""
from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction as Fr


@dataclass(frozen=True)
class Tableau:
    """A Runge-Kutta tableau with exact rational entries where they exist.

    Checks on construction: rows of A sum to c, sum(b) = 1, and the order conditions up to
    min(order, 4) (higher orders are checked by the registry-wide order test).
    """

    a: tuple[tuple[Fr, ...], ...]
    b: tuple[Fr, ...]
    c: tuple[Fr, ...]
    order: int

    def __post_init__(self):
        s = len(self.b)
        if len(self.a) != s or any(len(row) != s for row in self.a) or len(self.c) != s:
            raise ValueError("tableau shapes do not match")
        for i in range(s):
            if abs(sum(self.a[i]) - self.c[i]) > 1e-14:   # float data (DOP853) sums to ~1e-15
                raise ValueError(f"row {i} of A does not sum to c_{i}")
        b, c, a = self.b, self.c, self.a
        p_max = min(self.order, 4)
        conditions = [(1, sum(b), 1)]
        if p_max >= 2:
            conditions.append((2, sum(b[i] * c[i] for i in range(s)), Fr(1, 2)))
        if p_max >= 3:
            conditions.append((3, sum(b[i] * c[i] ** 2 for i in range(s)), Fr(1, 3)))
            conditions.append((3, sum(b[i] * a[i][j] * c[j] for i in range(s) for j in range(s)),
                               Fr(1, 6)))
        if p_max >= 4:
            conditions.append((4, sum(b[i] * c[i] ** 3 for i in range(s)), Fr(1, 4)))
            conditions.append((4, sum(b[i] * c[i] * a[i][j] * c[j] for i in range(s)
                                      for j in range(s)), Fr(1, 8)))
            conditions.append((4, sum(b[i] * a[i][j] * c[j] ** 2 for i in range(s)
                                      for j in range(s)), Fr(1, 12)))
            conditions.append((4, sum(b[i] * a[i][j] * a[j][k] * c[k] for i in range(s)
                                      for j in range(s) for k in range(s)), Fr(1, 24)))
        for p, got, want in conditions:
            if abs(got - want) > 1e-14:
                raise ValueError(f"order-{p} condition fails: {got} != {want}")

    @property
    def stages(self) -> int:
        return len(self.b)

    @property
    def explicit(self) -> bool:
        return all(self.a[i][j] == 0 for i in range(self.stages) for j in range(i, self.stages))


def tableau(a, b, c, order) -> Tableau:
    """Build a Tableau from nested lists of ints, Fractions or strings like '1/6'."""
    def conv(x):
        return Fr(x) if isinstance(x, (int, str, Fr)) else Fr(float(x))
    return Tableau(tuple(tuple(conv(x) for x in row) for row in a), tuple(conv(x) for x in b),
                   tuple(conv(x) for x in c), order)


def lit(x) -> str:
    """A coefficient as a float literal that numba folds as a constant (nearest double)."""
    return repr(float(x))
