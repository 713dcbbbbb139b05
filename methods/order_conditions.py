"""Runge-Kutta order conditions over rooted trees, checked in exact arithmetic.

A tableau (A, b) has order p when Σ_i b_i Φ_i(t) = 1/γ(t) for every rooted tree t with |t| ≤ p
nodes (Butcher 1963; HNW I §II.2, Thm 2.13; [HLW] III.1): Φ_i(τ) = 1 and
Φ_i([t_1, ..., t_m]) = Π_k Σ_j a_ij Φ_j(t_k) are the elementary weights, γ the tree's density.
A continuous extension u(θ) = y0 + h Σ_j b_j(θ) k_j has order p when Σ_j b_j(θ) Φ_j(t) =
θ^|t| / γ(t) as polynomials in θ (HNW I §II.6). The trees (1, 1, 2, 4, 9, 20, 48, 115, 286, 719,
1842, 4766 of orders 1..12) are generated once.

Entries are exact: ``Fraction`` (rationals, and decimal strings converted digit for digit, e.g.
Feagin's 60-digit tables) or :class:`Surd` (p + q√d, e.g. Verner's 9(8) pair in Q(√6), Gauss in
Q(√3)). The sums are formed in integers: every coefficient times the common denominator D of its
matrix, so Φ(t) of a tree with k nodes carries D^(k-1) and no gcd is ever taken. Data given only as
decimals cannot satisfy the conditions exactly; ``tol`` bounds |Σ b_i Φ_i(t) - 1/γ(t)|.

:func:`check` is a plain function of (A, b, c, order) returning the failing conditions (empty
when the tableau has the order), as the user tableaus of the spec parser need it too.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from decimal import Decimal, localcontext
from fractions import Fraction
from functools import cache

MAX_ORDER = 12


class Surd:
    """p + q √d with rational (or, scaled, integer) p, q and a square-free integer d > 1."""

    __slots__ = ("d", "p", "q")

    def __init__(self, p, q, d: int):
        self.p, self.q, self.d = p, q, d

    def _co(self, o):
        if isinstance(o, Surd):
            if o.d != self.d:
                raise ValueError(f"surds of √{self.d} and √{o.d} do not mix")
            return o.p, o.q
        return o, 0

    def __add__(self, o):
        p, q = self._co(o)
        return Surd(self.p + p, self.q + q, self.d)

    __radd__ = __add__

    def __sub__(self, o):
        p, q = self._co(o)
        return Surd(self.p - p, self.q - q, self.d)

    def __rsub__(self, o):
        return -self + o

    def __neg__(self):
        return Surd(-self.p, -self.q, self.d)

    def __mul__(self, o):
        p, q = self._co(o)
        return Surd(self.p * p + self.d * self.q * q, self.p * q + self.q * p, self.d)

    __rmul__ = __mul__

    def __eq__(self, o):
        p, q = self._co(o) if isinstance(o, (Surd, int, Fraction)) else (None, None)
        return p is not None and self.p == p and self.q == q

    def __hash__(self):
        return hash(self.p) if self.q == 0 else hash((self.p, self.q, self.d))

    def decimal(self, digits: int = 60) -> Decimal:
        with localcontext() as ctx:
            ctx.prec = digits
            return _dec(self.p) + _dec(self.q) * Decimal(self.d).sqrt()

    def __float__(self):
        return float(self.decimal())

    def __abs__(self):
        return abs(self.decimal())

    def __repr__(self):
        return f"{self.p}{'+' if self.q >= 0 else '-'}{abs(self.q)}*sqrt({self.d})"


def _dec(x) -> Decimal:
    x = Fraction(x)
    return Decimal(x.numerator) / Decimal(x.denominator)


def number(x):
    """An exact coefficient from an int, a Fraction, a Surd, or a string: '3/50', a decimal
    ('-.2943e-1', converted digit for digit) or 'p + q*sqrt(d)' with rational p, q."""
    if isinstance(x, (int, Fraction, Surd)):
        return x
    if isinstance(x, float):
        return Fraction(x)                      # the double itself, exactly
    s = str(x).replace(" ", "")
    if "sqrt(" in s:
        head, d = s.split("*sqrt(")
        d = int(d.rstrip(")"))
        cut = max(head.rfind("+"), head.rfind("-"))
        while cut > 0 and head[cut - 1] in "eE":        # an exponent's sign, not the split
            cut = max(head.rfind("+", 0, cut - 1), head.rfind("-", 0, cut - 1))
        if cut <= 0:
            return Surd(Fraction(0), Fraction(head), d)
        return Surd(Fraction(head[:cut]), Fraction(head[cut:]), d)
    return Fraction(s)


# -- trees ------------------------------------------------------------------------------------------


def grow(order: int, colours: tuple, node) -> tuple[tuple[tuple, ...], ...]:
    """The rooted trees with k = 1..order nodes, one tuple per k, each tree made by
    ``node(colour, children)`` for every colour (the children in non-decreasing (size, index)
    order, so each tree has one representation). Shared by :func:`trees` and the bicoloured
    trees of :mod:`.prk_conditions`."""
    by_size: dict[int, list] = {1: [node(colour, ()) for colour in colours]}

    def forests(m, lowest):
        if m == 0:
            yield ()
            return
        for size in range(1, m + 1):
            for index, tree in enumerate(by_size[size]):
                if (size, index) >= lowest:
                    for rest in forests(m - size, (size, index)):
                        yield (tree,) + rest

    for n in range(2, order + 1):
        by_size[n] = [node(colour, kids) for colour in colours for kids in forests(n - 1, (0, 0))]
    return tuple(tuple(by_size[k]) for k in range(1, order + 1))


@cache
def trees(order: int) -> tuple[tuple[tuple, ...], ...]:
    """trees(p)[k-1]: the rooted trees with k nodes, k = 1..p. A tree is the tuple of its root's
    subtrees in non-decreasing (size, index) order, so each tree has one representation."""
    if not 1 <= order <= MAX_ORDER:
        raise ValueError(f"order {order}: trees are generated up to order {MAX_ORDER}")
    return grow(order, (None,), lambda colour, kids: kids)


@cache
def nodes(tree: tuple) -> int:
    return 1 + sum(nodes(c) for c in tree)


@cache
def density(tree: tuple) -> int:
    """γ(t) = |t| Π γ(t_k) over the subtrees."""
    return nodes(tree) * math.prod(density(c) for c in tree)


def bracket(tree: tuple) -> str:
    """Butcher's notation: τ, [τ], [[τ],τ], [τ²] for [τ,τ] (larger subtrees first)."""
    if not tree:
        return "τ"
    parts, kids = [], sorted(tree, key=lambda c: (nodes(c), c), reverse=True)
    for c in dict.fromkeys(kids):
        m = kids.count(c)
        parts.append(bracket(c) + ("" if m == 1 else _sup(m)))
    return "[" + ",".join(parts) + "]"


def _sup(m: int) -> str:
    return str(m).translate(str.maketrans("0123456789", "⁰¹²³⁴⁵⁶⁷⁸⁹"))


def expression(tree: tuple, weights: str = "b") -> str:
    """Σ b_i Φ_i(t) written out, e.g. Σ b_i c_i a_ij c_j for [[τ],τ]."""
    letters = iter("ijklmnopqrsuvwxyz")

    def factors(t, i):
        leaves = sum(1 for c in t if not c)
        out = [f"c_{i}" + ("" if leaves == 1 else _sup(leaves))] if leaves else []
        for c in t:
            if c:
                j = next(letters)
                out += [f"a_{i}{j}"] + factors(c, j)
        return out

    root = next(letters)
    return "Σ " + " ".join([f"{weights}_{root}"] + factors(tree, root))


# -- checking ---------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Failure:
    """One condition that does not hold: its order, tree, the sum as written, its value and the
    value it should have (``power`` of θ for a continuous extension)."""

    order: int
    tree: str
    expression: str
    got: object
    want: object
    power: int | None = None

    def __str__(self):
        got = self.got
        if not isinstance(got, (Fraction, int)) or Fraction(got).denominator > 10 ** 12:
            got = f"{float(got):.17g}"                 # the exact value of float data is unreadable
        where = "" if self.power is None else f" (coefficient of θ^{self.power})"
        if self.order == 0:
            return f"row sum: {self.expression} = {got} ≠ {self.want}"
        return (f"order {self.order} condition for tree {self.tree}{where}: {self.expression} = "
                f"{got} ≠ {self.want}")


def _denominator(x) -> int:
    if isinstance(x, Surd):
        return math.lcm(Fraction(x.p).denominator, Fraction(x.q).denominator)
    return Fraction(x).denominator


def _scaled(values, den: int):
    out = []
    for x in values:
        if isinstance(x, Surd):
            p, q = Fraction(x.p) * den, Fraction(x.q) * den
            out.append(Surd(p.numerator, q.numerator, x.d))
        else:
            out.append((Fraction(x) * den).numerator)
    return out


def _ring(values) -> tuple[int, list]:
    """(D, D * values) in integers when the common denominator D is small enough for the powers
    D^(k-1) to stay cheap; else (1, values) as they are (reduced fractions grow slower than the
    powers of a 400-digit D: Verner 9(8)'s surds)."""
    den = math.lcm(*(_denominator(x) for x in values)) if values else 1
    if den > 10 ** 80:
        return 1, list(values)
    return den, _scaled(values, den)


def _small(residual, tol) -> bool:
    if tol == 0:
        return residual == 0
    return abs(residual) <= tol


def _weights_table(a, order: int):
    """Integer elementary weights: {tree: (D^(|t|-1) Φ_j(t))_j} for |t| <= order, and D."""
    s = len(a)
    den, ai = _ring([x for row in a for x in row])
    ai = [ai[i * s:(i + 1) * s] for i in range(s)]
    nz = [[(j, ai[i][j]) for j in range(s) if ai[i][j] != 0] for i in range(s)]
    table, a_times = {(): [1] * s}, {}
    for level in trees(order)[1:]:
        for tree in level:
            v = None
            for child in tree:
                if child not in a_times:
                    w = table[child]
                    a_times[child] = [sum((x * w[j] for j, x in nz[i]), 0) for i in range(s)]
                u = a_times[child]
                v = list(u) if v is None else [x * y for x, y in zip(v, u)]
            table[tree] = v
    return table, den


def _conditions(a, weight_rows, order: int, tol, start: int = 1):
    """Failures of Σ_j w_j Φ_j(t) = [power = |t|] / γ(t) for each (power, w) of weight_rows and
    each tree with start <= |t| <= order (power None: the plain condition, power |t|)."""
    table, den = _weights_table(a, order)
    tol = Fraction(tol) if tol else 0
    out = []
    for power, w in weight_rows:
        wden, wi = _ring(w)
        nzw = [(j, x) for j, x in enumerate(wi) if x != 0]
        for k in range(start, order + 1):
            scale = Fraction(wden) * Fraction(den) ** (k - 1)
            for tree in trees(order)[k - 1]:
                phi = table[tree]
                total = sum((x * phi[j] for j, x in nzw), 0)
                want = Fraction(1, density(tree)) if power in (None, k) else Fraction(0)
                got = _unscale(total, scale)
                if not _small(got - want, tol):
                    out.append(Failure(k, bracket(tree), expression(tree), got, want, power))
    return out


def _unscale(total, scale: Fraction):
    if isinstance(total, Surd):
        return Surd(Fraction(total.p) / scale, Fraction(total.q) / scale, total.d)
    return Fraction(total) / scale


def check(a, b, c=None, order: int = 1, tol=0) -> list[Failure]:
    """The order conditions up to ``order`` of the tableau (A, b) that fail, and the rows of A
    that do not sum to c (when c is given); [] when the tableau has the order. Entries: anything
    :func:`number` takes. ``tol`` = 0 demands exact equality; decimal data needs a tolerance."""
    a = [[number(x) for x in row] for row in a]
    b = [number(x) for x in b]
    s = len(b)
    if len(a) != s or any(len(row) != s for row in a):
        raise ValueError(f"tableau shapes do not match: A is {len(a)} rows, b has {s} entries")
    if not 1 <= order <= MAX_ORDER:
        raise ValueError(f"order {order}: conditions are checked up to order {MAX_ORDER}")
    out = []
    if c is not None:
        c = [number(x) for x in c]
        tol_c = Fraction(tol) if tol else 0
        for i in range(s):
            total = sum(a[i], Fraction(0))
            if not _small(total - c[i], tol_c):
                out.append(Failure(0, "", f"Σ_j a_{i + 1}j (row {i + 1})", total, c[i]))
    return out + _conditions(a, [(None, b)], order, tol)


def check_dense(a, b_theta, order: int, tol=0) -> list[Failure]:
    """Failing conditions of a continuous extension: ``b_theta[j][p]`` is the coefficient of
    θ^p in b_j(θ), over every stage of ``a`` (the pair's and the extra ones)."""
    a = [[number(x) for x in row] for row in a]
    degree = max(len(row) for row in b_theta) - 1
    rows = []
    for p in range(degree + 1):
        rows.append((p, [number(row[p]) if p < len(row) else Fraction(0) for row in b_theta]))
    return _conditions(a, rows, order, tol)


def order_of(a, b, tol=0, limit: int = MAX_ORDER) -> int:
    """The largest p <= limit for which every condition up to p holds."""
    for p in range(1, limit + 1):
        if check(a, b, None, p, tol):
            return p - 1
    return limit
