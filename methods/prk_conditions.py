"""Order conditions of partitioned Runge-Kutta methods over bicoloured rooted trees.

A partitioned RK method (A, b) for u' = f(u, v) and (Â, b̂) for v' = g(u, v) has order p when
Σ_i b_i^(r) Φ_i(t) = 1/γ(t) for every bicoloured rooted tree t with |t| ≤ p nodes ([HLW] III.2.1,
Thm 2.4; HNW I §II.15): a vertex of colour u stands for f, of colour v for g; b^(r) is b or b̂ after
the root's colour; Φ_i(τ) = 1 and Φ_i(t) = Π_k Σ_j a^(k)_ij Φ_j(t_k), with a^(k) = A or Â after
the colour of the subtree t_k's root; γ is the density of the uncoloured tree. With A = Â, b = b̂
these are the conditions of the Runge-Kutta method, each repeated for every colouring.

:func:`check` takes exact entries (``Fraction``; the check is then exact, or within an absolute
``tol`` for entries given to many digits) or floats (then a
condition holds when |Σ b Φ − 1/γ| ≤ ``rtol`` (Σ |b| |Φ| + 1/γ), for coefficients known only to
double precision, such as compositions with irrational steps).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction
from functools import cache

import numpy as np

from gnibench.methods.order_conditions import grow

MAX_ORDER = 10
COLOURS = ("u", "v")


@cache
def trees(order: int) -> tuple[tuple[tuple, ...], ...]:
    """trees(p)[k-1]: the bicoloured rooted trees with k nodes; a tree is (colour, children)
    with the children in a fixed order (by size, then index), so each tree has one form."""
    if not 1 <= order <= MAX_ORDER:
        raise ValueError(f"order {order}: bicoloured trees are generated up to {MAX_ORDER}")
    return grow(order, (0, 1), lambda colour, kids: (colour, kids))


@cache
def nodes(tree: tuple) -> int:
    return 1 + sum(nodes(c) for c in tree[1])


@cache
def density(tree: tuple) -> int:
    return nodes(tree) * math.prod(density(c) for c in tree[1])


def notation(tree: tuple) -> str:
    """``u[v,u[v]]``: a vertex's colour, then its subtrees in brackets."""
    colour, kids = tree
    return COLOURS[colour] + ("[" + ",".join(notation(c) for c in kids) + "]" if kids else "")


@dataclass(frozen=True)
class Failure:
    order: int
    tree: str
    got: object
    want: object

    def __str__(self):
        got = self.got if isinstance(self.got, (int, Fraction)) else f"{float(self.got):.17g}"
        return (f"order {self.order} condition for the bicoloured tree {self.tree}: "
                f"Σ b Φ = {got} ≠ {self.want}")


def check(u: tuple, v: tuple, order: int, rtol: float | None = None, tol=0) -> list[Failure]:
    """The failing conditions up to ``order`` of the partitioned tableau ``u`` = (A, b) and
    ``v`` = (Â, b̂), each A a list of rows: in exact arithmetic (``rtol`` None; a condition holds
    when |Σ b Φ − 1/γ| ≤ ``tol``, 0 by default, for entries known to many digits only), else in
    double precision with the relative tolerance ``rtol``."""
    exact = rtol is None
    mats, weights = [], []
    for a, b in (u, v):
        if exact:
            mats.append([[Fraction(x) for x in row] for row in a])
            weights.append([Fraction(x) for x in b])
        else:
            mats.append(np.array(a, dtype=float))
            weights.append(np.array(b, dtype=float))
    s = len(weights[0])
    if any(len(w) != s for w in weights) or any(len(m) != s for m in mats):
        raise ValueError("the two tableaus must have the same number of stages")
    phi: dict[tuple, object] = {}
    a_phi: dict[tuple, object] = {}
    absphi: dict[tuple, object] = {}
    a_abs: dict[tuple, object] = {}
    out = []
    for k, level in enumerate(trees(order), 1):
        for tree in level:
            colour, kids = tree
            if exact:
                vec = [Fraction(1)] * s
                for c in kids:
                    if c not in a_phi:
                        m, w = mats[c[0]], phi[c]
                        a_phi[c] = [sum((m[i][j] * w[j] for j in range(s) if m[i][j]),
                                        Fraction(0)) for i in range(s)]
                    vec = [x * y for x, y in zip(vec, a_phi[c])]
                phi[tree] = vec
                got = sum((x * y for x, y in zip(weights[colour], vec)), Fraction(0))
                want = Fraction(1, density(tree))
                ok = abs(got - want) <= tol
            else:
                vec, mag = np.ones(s), np.ones(s)
                for c in kids:
                    if c not in a_phi:
                        a_phi[c] = mats[c[0]] @ phi[c]
                        a_abs[c] = np.abs(mats[c[0]]) @ absphi[c]
                    vec, mag = vec * a_phi[c], mag * a_abs[c]
                phi[tree], absphi[tree] = vec, mag
                got = float(weights[colour] @ vec)
                want = 1.0 / density(tree)
                scale = float(np.abs(weights[colour]) @ mag) + want
                ok = abs(got - want) <= rtol * scale
                want = Fraction(1, density(tree))
            if not ok:
                out.append(Failure(k, notation(tree), got, want))
    return out
