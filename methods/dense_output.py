"""Continuous extensions of embedded pairs (dense output), as data plus one generator.

An accepted step y0 -> y1 of size h, with stages K_0 = f(y0), ..., K_{s-1} = f(y1) (the pair's
tableau ends with f(y1)) and possibly extra stages K_s, ..., is extended to
u(θ) = y0 + θ (F0 + (1-θ) (F1 + θ (F2 + (1-θ) (F3 + θ (F4 + ...))))),   0 <= θ <= 1,
with F0 = y1 - y0, F1 = h K_0 - F0, F2 = F0 - h K_{s-1} - F1 and F_r = h Σ_j d_{r-3, j} K_j
(r >= 3): Hairer's CONTD5 (DOPRI5, 4th order, HNW I §II.6) and CONTD8 (DOP853, 7th
order with 3 extra stages). So u(0) = y0, u(1) = y1, u'(0) = h f(y0), u'(1) = h f(y1) by
construction. The record holds d (and the extra stages); :meth:`DenseOutput.check` verifies on
construction that u(θ) = y0 + h Σ_j b_j(θ) K_j satisfies every order condition up to ``order`` as
a polynomial identity in θ (Σ_j b_j(θ) Φ_j(t) = θ^|t| / γ(t) for every rooted tree t, HNW I §II.2
and §II.6), exactly for rational data. Its text (``dense_from_stages``, ``dense_eval``,
``dense_slope``) is written by methods/assembly/steps/dense.py.
"""
from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

from gnibench.methods import order_conditions as oc
from gnibench.methods.tableau import require, verdict

# -- order conditions (trees and densities: methods/order_conditions.py) -------------------------


def elementary_weights(a, tree: tuple, memo: dict | None = None) -> list:
    """Φ_j(t) for every stage j, in the entries' own number type (floats for a quick residual):
    Φ(leaf) = 1, Φ([t1..tm]) = Π_k A Φ(t_k) componentwise (``memo`` keeps A Φ of the subtrees)."""
    memo = {} if memo is None else memo
    s = len(a)
    v = [1] * s
    for child in tree:
        if child not in memo:
            pc = elementary_weights(a, child, memo)
            memo[child] = [sum(a[i][j] * pc[j] for j in range(s) if a[i][j] != 0) for i in range(s)]
        v = [x * y for x, y in zip(v, memo[child])]
    return v


# -- the record -------------------------------------------------------------------------------------


def _poly_mul(p, q):
    out = [0] * (len(p) + len(q) - 1)
    for i, x in enumerate(p):
        for j, y in enumerate(q):
            out[i + j] += x * y
    return out


@dataclass(frozen=True)
class DenseOutput:
    """A pair's continuous extension, in one of two forms:

    * Hairer's (DOPRI5, DOP853): the rows ``d`` of F3, F4, ... over all stages (the pair's, then
      the extra ones); the pair's last stage is f(y1);
    * polynomial weights (Verner's interpolants): ``b_theta[j]`` = (r_j1, ..., r_jq), the
      coefficients of θ^1..θ^q in b_j(θ), so u(θ) = y0 + h Σ_j b_j(θ) K_j.

    ``extra_a``/``extra_c``: the extra stages (rows of A over every earlier stage, and c); an extra
    stage whose row is b is f(y1), which the driver has already (not evaluated again). ``tol``:
    0 for exact data, else the bound on the order conditions' residuals (decimal data)."""

    order: int
    d: tuple[tuple, ...] = ()
    extra_a: tuple[tuple, ...] = ()
    extra_c: tuple = ()
    reference: str = ""
    b_theta: tuple[tuple, ...] = ()
    tol: float = 0

    @property
    def polynomial(self) -> bool:
        return bool(self.b_theta)

    def is_f1(self, i: int, tab) -> bool:
        """Extra stage i is f(y1): its row is b (and zero beyond the pair's stages)."""
        row = self.extra_a[i]
        return (list(row[:tab.stages]) == list(tab.b) and all(x == 0 for x in row[tab.stages:])
                and self.extra_c[i] == 1)

    def new_stages(self, tab) -> int:
        """f-evaluations per step beyond the pair's own and f(y1) (DOP853: 3, Vern9: 9)."""
        return sum(1 for i in range(len(self.extra_a)) if not self.is_f1(i, tab))

    @property
    def extra_stages(self) -> int:
        """Extra rows (stages) of the extension, f(y1) included when it is one of them."""
        return len(self.extra_a)

    @property
    def degree(self) -> int:
        return len(self.b_theta[0]) if self.polynomial else 3 + len(self.d)

    def stages_a(self, tab) -> list[list]:
        """A over all stages: the pair's tableau, then the extra rows."""
        total = tab.stages + self.extra_stages
        rows = [list(r) + [0] * self.extra_stages for r in tab.a]
        rows += [list(r) + [0] * (total - len(r)) for r in self.extra_a]
        return rows

    def weights(self, tab, num=Fraction) -> list[list]:
        """b_j(θ) as polynomial coefficients in θ (index = power), for every stage j, in the number
        type ``num`` (float for float data: exact rationals of doubles are slow to multiply)."""
        if self.polynomial:
            return [[num(0)] + [num(x) for x in row] for row in self.b_theta]
        s, total = tab.stages, tab.stages + self.extra_stages
        nest, cur = [], [1]                    # θ, θ(1-θ), θ²(1-θ), θ²(1-θ)², ...
        for r in range(self.degree):
            cur = _poly_mul(cur, [0, 1] if r % 2 == 0 else [1, -1])
            nest.append(cur)
        out = []
        for j in range(total):
            b = num(tab.b[j]) if j < s else num(0)
            coeff = [b, int(j == 0) - b, 2 * b - int(j == 0) - int(j == s - 1)]
            coeff += [num(row[j]) for row in self.d]
            poly = [0] * (self.degree + 1)
            for r, c in enumerate(coeff):
                for p, x in enumerate(nest[r]):
                    poly[p] += c * x
            out.append(poly)
        return out

    def residuals(self, tab, order: int) -> list[float]:
        """max over trees t with |t| = k and powers of θ of |Σ_j b_j(θ) Φ_j(t) - θ^k / γ(t)|,
        for k = 1..order, in floats (a quick look; :meth:`check` is exact)."""
        a = [[float(x) for x in row] for row in self.stages_a(tab)]
        w = self.weights(tab, float)
        out, memo = [], {}
        for k, trees in enumerate(oc.trees(order), start=1):
            worst = 0.0
            for tree in trees:
                phi = elementary_weights(a, tree, memo)
                for p in range(self.degree + 1):
                    got = sum(w[j][p] * phi[j] for j in range(len(phi)))
                    worst = max(worst, abs(got - (1.0 / oc.density(tree) if p == k else 0.0)))
            out.append(worst)
        return out

    def check(self, tab) -> None:
        """Raise ValueError unless the extension fits the tableau and has its stated order: every
        condition Σ_j b_j(θ) Φ_j(t) = θ^|t| / γ(t), |t| <= order, as a polynomial identity in θ,
        in exact arithmetic (methods/order_conditions.py), within ``tol`` for decimal data.

        DOP853's entries are 30-digit decimals rounded to doubles, with d entries up to 5e2 that
        cancel: its residuals measure 4.3e-12 (tol 1e-11); a wrong digit gives residuals > 1e-3."""
        s, total = tab.stages, tab.stages + self.extra_stages
        if not self.polynomial and (tab.c[s - 1] != 1 or list(tab.a[s - 1]) != list(tab.b)):
            raise ValueError("Hairer's form of dense output needs a tableau whose last stage is f(y1)")
        if len(self.extra_c) != self.extra_stages:
            raise ValueError("extra stages: one c per row")
        if (len(self.b_theta) != total if self.polynomial
                else any(len(row) != total for row in self.d)):
            raise ValueError("each row of the extension covers every stage, extra ones included")
        for i, (row, c) in enumerate(zip(self.extra_a, self.extra_c)):
            if len(row) != s + i or abs(sum(row) - c) > max(self.tol, 1e-14):
                raise ValueError(f"extra stage {i}: a row over the {s + i} earlier stages summing to c")
        weights = self.weights(tab, oc.number)             # b_j(θ) stage by stage
        require(verdict("dense", self.order, self.tol, self.stages_a(tab), weights),
                f"dense output of order {self.order}")
