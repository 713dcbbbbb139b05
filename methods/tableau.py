"""Butcher tableaus as validated, exact data ([HLW] II.1; diffrax-style checks in __post_init__).

Every tableau is checked on construction against all order conditions up to its order
(methods/order_conditions.py: rooted trees, exact arithmetic). A verdict is kept by the hash of the
tableau's exact data: in the process, in the record of the shipped tableaus' verdicts
(methods/order_verdicts.json, recomputed by the tests) and in the disk cache (``order-conditions/``,
checksummed like every entry), so importing the registry does not redo the high-order checks
(Verner 9(8) in Q(√6) and Feagin's 60-digit decimals: ~5 s of CPU).
"""
from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

from gnibench.methods import order_conditions as oc
from gnibench.suite.foundation import cache

CHECKER_VERSION = "1"          # bump when the checker changes: the cached verdicts are then unused
_VERDICTS: dict[str, list[str]] = {}
_SHIPPED_PATH = Path(__file__).with_name("order_verdicts.json")
_SHIPPED: set[str] | None = None
SEEN: set[str] = set()          # every key asked for in this process (the registry's, at import)


def verdict_key(kind: str, order: int, tol, *data) -> str:
    text = json.dumps([CHECKER_VERSION, kind, order, str(tol), data], default=str)
    return hashlib.sha256(text.encode()).hexdigest()


def shipped_verdicts() -> set[str]:
    """Keys of the shipped tableaus' passing verdicts (methods/order_verdicts.json): the exact data
    of every tableau, estimate and extension of the registry, hashed with the checker's version.
    tests/methods/test_order_conditions.py recomputes each of them from scratch and checks that the file
    lists exactly the registry's keys, so a changed coefficient is never covered by it. After a
    change to a shipped tableau (its checks pass on import), write the file again with
    ``python -c "import gnibench.methods.tableau as t, gnibench.methods, json;
    json.dump(sorted(t.SEEN), open(t._SHIPPED_PATH, 'w'), indent=0)"``."""
    global _SHIPPED
    if _SHIPPED is None:
        _SHIPPED = set(json.loads(_SHIPPED_PATH.read_text()))
    return _SHIPPED


def verdict(kind: str, order: int, tol, *data) -> list[str]:
    """The failing conditions (as text) of ``oc.check`` (kind 'tableau': data = A, b, c) or
    ``oc.check_dense`` (kind 'dense': data = A, b(θ)), cached by the hash of the exact data."""
    key = verdict_key(kind, order, tol, *data)
    SEEN.add(key)
    if key in _VERDICTS:
        return _VERDICTS[key]
    if key in shipped_verdicts():
        return []
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


class TableauShape:
    """The shape of a tableau with fields ``a`` and ``b`` (shared with the user tableaus of
    suite/cell/user/methods.py)."""

    @property
    def stages(self) -> int:
        return len(self.b)

    @property
    def explicit(self) -> bool:
        return all(self.a[i][j] == 0 for i in range(self.stages) for j in range(i, self.stages))


@dataclass(frozen=True)
class Tableau(TableauShape):
    """A Runge-Kutta tableau with exact entries (Fraction, or Surd p + q√d) where they exist.

    Checks on construction: the rows of A sum to c and every order condition up to ``order``
    holds, exactly, or within ``tol`` for data known only as decimals or doubles (DOP853's).
    """

    a: tuple[tuple, ...]
    b: tuple
    c: tuple
    order: int
    tol: float = 0
    round_to_sums: bool = False    # doubles for the kernels: see `doubles`

    def __post_init__(self):
        s = len(self.b)
        if len(self.a) != s or any(len(row) != s for row in self.a) or len(self.c) != s:
            raise ValueError("tableau shapes do not match")
        require(verdict("tableau", self.order, self.tol, self.a, self.b, self.c),
                f"tableau of order {self.order}")

    @property
    def doubles(self) -> tuple[tuple[tuple[float, ...], ...], tuple[float, ...]]:
        """(A, b) as the doubles the kernels use: each entry's nearest double; with
        ``round_to_sums`` the first non-zero entry of each row of A (of b) is instead the nearest
        double to c_i (to 1) minus the exact sum of the other rounded entries. Tableaus with large
        cancelling entries (Vern6: |a_ij| ~ 208, b_7 ~ -176, b_8 ~ 172) otherwise break the low
        order conditions in doubles (Vern6: Σ b_i c_i - 1/2 = 6.5e-12, an O(h) error at 1e-12;
        with the sums kept: 3.7e-13)."""
        def rounded(row, target):
            out = [float(x) for x in row]
            nz = [j for j, x in enumerate(row) if x != 0]
            if self.round_to_sums and len(nz) > 1:
                rest = sum((Fraction(out[j]) for j in nz[1:]), Fraction(0))
                out[nz[0]] = float(Fraction(float(target)) - rest) if isinstance(target, oc.Surd) \
                    else float(Fraction(target) - rest)
            return tuple(out)
        return (tuple(rounded(row, c) for row, c in zip(self.a, self.c)), rounded(self.b, 1))


def tableau(a, b, c, order, tol=0) -> Tableau:
    """Build a Tableau from nested lists of ints, Fractions or strings like '1/6', '-.25e-1' or
    '1/2-1/6*sqrt(3)' (oc.number); floats are taken as the exact value of the double."""
    return Tableau(tuple(tuple(oc.number(x) for x in row) for row in a),
                   tuple(oc.number(x) for x in b), tuple(oc.number(x) for x in c), order, tol)


def lit(x) -> str:
    """A coefficient as a float literal that numba folds as a constant (nearest double)."""
    return repr(float(x))


def weighted(h: str, terms, n: int) -> list[str]:
    """``h * (c0 * v0[i] + c1 * v1[i] + ...)`` for i < n, over the (coefficient, stage name)
    ``terms``: the increment of a Runge-Kutta stage or step, [HLW] (1.5)-(1.7), II.1.1, as source
    text written where it is used."""
    return [f"{h} * (" + " + ".join(f"{lit(c)} * {v}[{i}]" for c, v in terms) + ")"
            for i in range(n)]

