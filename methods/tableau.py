"""Butcher tableaus as validated, exact data ([HLW] II.1; diffrax-style checks in __post_init__).

Every tableau is checked on construction against all order conditions up to its order
(methods/order_conditions.py: rooted trees, exact arithmetic). A verdict is kept by the hash of the
tableau's exact data, in the process and in the disk cache (``order-conditions/``, checksummed like
every entry), so importing the registry does not redo the high-order checks (Verner 9(8) in Q(√6):
~1 s the first time).
"""
from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass

from gnibench.methods import order_conditions as oc
from gnibench.suite.foundation import cache

CHECKER_VERSION = "1"          # bump when the checker changes: the cached verdicts are then unused
_VERDICTS: dict[str, list[str]] = {}


def verdict(kind: str, order: int, tol, *data) -> list[str]:
    """The failing conditions (as text) of ``oc.check`` (kind 'tableau': data = A, b, c) or
    ``oc.check_dense`` (kind 'dense': data = A, b(θ)), cached by the hash of the exact data."""
    text = json.dumps([CHECKER_VERSION, kind, order, str(tol), data], default=str)
    key = hashlib.sha256(text.encode()).hexdigest()
    if key in _VERDICTS:
        return _VERDICTS[key]
    path = cache.cache_dir("order-conditions") / f"{key}.json"
    raw = cache.read_checked(path, "an order-condition verdict")
    if raw is not None:
        found = json.loads(raw)
    else:
        if kind == "tableau":
            failures = oc.check(*data, order=order, tol=tol)
        else:
            failures = oc.check_dense(*data, order=order, tol=tol)
        found = [str(f) for f in failures]
        cache.write_checked(path, json.dumps(found))
    _VERDICTS[key] = found
    return found


def require(found: list[str], what: str) -> None:
    if found:
        more = f" (and {len(found) - 3} more)" if len(found) > 3 else ""
        raise ValueError(f"{what}: " + "; ".join(found[:3]) + more)


@dataclass(frozen=True)
class Tableau:
    """A Runge-Kutta tableau with exact entries (Fraction, or Surd p + q√d) where they exist.

    Checks on construction: the rows of A sum to c and every order condition up to ``order``
    holds, exactly, or within ``tol`` for data known only as decimals or doubles (DOP853's).
    """

    a: tuple[tuple, ...]
    b: tuple
    c: tuple
    order: int
    tol: float = 0

    def __post_init__(self):
        s = len(self.b)
        if len(self.a) != s or any(len(row) != s for row in self.a) or len(self.c) != s:
            raise ValueError("tableau shapes do not match")
        require(verdict("tableau", self.order, self.tol, self.a, self.b, self.c),
                f"tableau of order {self.order}")

    @property
    def stages(self) -> int:
        return len(self.b)

    @property
    def explicit(self) -> bool:
        return all(self.a[i][j] == 0 for i in range(self.stages) for j in range(i, self.stages))


def tableau(a, b, c, order, tol=0) -> Tableau:
    """Build a Tableau from nested lists of ints, Fractions or strings like '1/6', '-.25e-1' or
    '1/2-1/6*sqrt(3)' (oc.number); floats are taken as the exact value of the double."""
    return Tableau(tuple(tuple(oc.number(x) for x in row) for row in a),
                   tuple(oc.number(x) for x in b), tuple(oc.number(x) for x in c), order, tol)


def lit(x) -> str:
    """A coefficient as a float literal that numba folds as a constant (nearest double)."""
    return repr(float(x))

