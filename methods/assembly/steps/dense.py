"""Dense output written out for a cell: the continuous extension of an embedded pair's step.

The record and its order checks are methods/dense_output.py (Hairer's CONTD5/CONTD8 form, or
Verner's polynomial weights); this module writes ``dense_from_stages`` (the coefficients from the
step's stages and the extra stages), ``dense_eval`` (u(θ)) and ``dense_slope`` (du/dθ), unrolled
over the N components, for the dense-output drivers (``integrate_dense``,
``adaptive_section_dense``) and ``dense_coeffs`` (templates/pair.py).
"""
from __future__ import annotations

from gnibench.methods import order_conditions as oc
from gnibench.methods.assembly.source import ENTRY, INTERNAL
from gnibench.methods.assembly.steps.erk import lincomb
from gnibench.methods.tableau import lit


def _stage_lines(dense: DenseOutput, tab, count: int, hairer: bool, n: int) -> list[str]:
    """The head of ``dense_from_stages``: the step's ``count`` stages unpacked, f(y1) as the last
    stage (always in Hairer's form; for polynomial weights when the pair is FSAL, and for every
    extra stage that is f(y1)), the extra stages evaluated."""
    s = tab.stages
    a_all = dense.stages_a(tab)
    unpack = ", ".join(f"k{j}" for j in range(count)) + ("," if count == 1 else "")
    lines = [f"\n{INTERNAL}\ndef dense_from_stages(y, y1, h, par, ks, f1):", f"    {unpack} = ks"]
    if hairer or count < s:
        lines.append(f"    k{s - 1} = f1")                  # an FSAL pair's last stage
    for i in range(s, s + dense.extra_stages):
        if not hairer and dense.is_f1(i - s, tab):
            lines.append(f"    k{i} = f1")
            continue
        terms = [(a_all[i][j], f"k{j}") for j in range(i) if a_all[i][j] != 0]
        lines.append(f"    k{i} = f({lincomb('y', 'h', terms, n)}, par)")
    return lines


def generate_dense(dense: DenseOutput, tab, count: int, n: int) -> str:
    """Source of ``dense_from_stages``, ``dense_eval`` and ``dense_slope`` for an n-dimensional
    cell.

    ``dense_from_stages(y, y1, h, par, ks, f1)`` takes the ``count`` stages the step computed
    (``ks``) and f(y1), evaluates the extra stages, and returns the coefficients (y0, F0, F1, ...).
    ``dense_eval(cf, θ)`` is u(θ) (Hairer's CONTD5/CONTD8 nesting); ``dense_slope(cf, θ)`` is
    du/dθ (= h u'(t) in time), for Newton on a section function.
    """
    if dense.polynomial:
        return _generate_polynomial(dense, tab, count, n)
    s, comma = tab.stages, "," if n == 1 else ""
    lines = _stage_lines(dense, tab, count, True, n)

    def tup(items):
        return "(" + ", ".join(items) + comma + ")"

    lines.append("    dy = " + tup(f"y1[{i}] - y[{i}]" for i in range(n)))
    lines.append("    bspl = " + tup(f"h * k0[{i}] - dy[{i}]" for i in range(n)))
    lines.append("    curv = " + tup(f"dy[{i}] - h * k{s - 1}[{i}] - bspl[{i}]" for i in range(n)))
    names = ["y", "dy", "bspl", "curv"]
    for r, row in enumerate(dense.d):
        terms = [(c, j) for j, c in enumerate(row) if c != 0]
        lines.append(f"    dd{r} = " + tup("h * (" + " + ".join(f"{lit(c)} * k{j}[{i}]" for c, j in terms)
                                            + ")" for i in range(n)))
        names.append(f"dd{r}")
    lines.append(f"    return ({', '.join(names)})")

    m = dense.degree
    cf = ", ".join(f"c{r}" for r in range(m + 1))

    def nested(i, r=0):
        w = "theta" if r % 2 == 0 else "s1"
        inner = f"c{r + 1}[{i}]" if r == m - 1 else f"(c{r + 1}[{i}] + {nested(i, r + 1)})"
        return f"{w} * {inner}"

    lines += [f"\n{ENTRY}\ndef dense_eval(cf, theta):", "    s1 = 1.0 - theta",
              f"    {cf} = cf", "    return " + tup(f"c0[{i}] + {nested(i)}" for i in range(n))]
    # du/dθ by forward differentiation of the nesting S_r = w_r (F_r + S_{r+1}), w_r = θ or 1 - θ
    lines += [f"\n{ENTRY}\ndef dense_slope(cf, theta):", "    s1 = 1.0 - theta",
              f"    {cf} = cf"]
    for i in range(n):
        last = m - 1
        w, sign = ("theta", "") if last % 2 == 0 else ("s1", "-")
        lines += [f"    v = c{m}[{i}]", f"    s = {w} * v", f"    ds = {sign}v"]
        for r in range(m - 2, -1, -1):
            w, sign = ("theta", "") if r % 2 == 0 else ("s1", "-")
            lines += [f"    v = c{r + 1}[{i}] + s", f"    ds = {sign}v + {w} * ds", f"    s = {w} * v"]
        lines.append(f"    du{i} = ds")
    lines.append("    return " + tup(f"du{i}" for i in range(n)))
    return "\n".join(lines) + "\n"


def _quotients(dense: DenseOutput, tab) -> list[list]:
    """q_j(θ) with b_j(θ) = θ b_j + θ (θ - 1) q_j(θ) (b_j = 0 beyond the pair's stages), by exact
    synthetic division; the remainder b_j(1) - b_j is 0 (within ``tol`` for decimal data)."""
    out = []
    for j, row in enumerate(dense.b_theta):
        d = [oc.number(x) for x in row]                 # (b_j(θ) - θ b_j) / θ: coefficients of θ^0..
        d[0] = d[0] - (tab.b[j] if j < tab.stages else 0)
        m = len(d) - 1
        q = [0] * m
        q[m - 1] = d[m]
        for k in range(m - 1, 0, -1):
            q[k - 1] = d[k] + q[k]
        remainder = d[0] + q[0]
        if abs(float(remainder)) > dense.tol * 1e6:            # 0 for exact data
            raise ValueError(f"interpolant weight of stage {j + 1}: b_j(1) differs from b_j by "
                             f"{float(remainder):.3g}")
        out.append(q)
    return out


def _generate_polynomial(dense: DenseOutput, tab, count: int, n: int) -> str:
    """The same three functions for polynomial weights, in the form
    u(θ) = y0 + θ (y1 - y0) + θ (θ - 1) Σ_k θ^k G_k,  G_k = h Σ_j q_jk K_j  (:func:`_quotients`),
    so that u(1) = y1 to round-off whatever the size of Verner's weights (Vern6's reach 1.2e5 and
    cancel to b_j: summed at θ = 1 in doubles they miss y1 by 8e-13 per step)."""
    comma = "," if n == 1 else ""
    lines = _stage_lines(dense, tab, count, False, n)

    def tup(items):
        return "(" + ", ".join(items) + comma + ")"

    q = _quotients(dense, tab)
    m = len(q[0])                                       # G_0 .. G_{m-1}
    lines.append("    dy = " + tup(f"y1[{i}] - y[{i}]" for i in range(n)))
    for k in range(m):
        terms = [(row[k], j) for j, row in enumerate(q) if row[k] != 0]
        lines.append(f"    g{k} = " + tup("h * (" + " + ".join(f"{lit(c)} * k{j}[{i}]" for c, j in terms)
                                           + ")" for i in range(n)))
    names = ["y", "dy"] + [f"g{k}" for k in range(m)]
    lines.append(f"    return ({', '.join(names)})")
    cf = ", ".join(names)

    def horner(i, k=0):                                 # S(θ) = Σ θ^k G_k
        return f"g{k}[{i}]" if k == m - 1 else f"g{k}[{i}] + theta * ({horner(i, k + 1)})"

    def dhorner(i, k=1):                                # S'(θ)
        return f"{k}.0 * g{k}[{i}]" if k == m - 1 else f"{k}.0 * g{k}[{i}] + theta * ({dhorner(i, k + 1)})"

    lines += [f"\n{ENTRY}\ndef dense_eval(cf, theta):", f"    {cf} = cf",
              "    return " + tup(f"y[{i}] + theta * (dy[{i}] + (theta - 1.0) * ({horner(i)}))"
                                  for i in range(n))]
    slope = (lambda i: f"dy[{i}] + (2.0 * theta - 1.0) * ({horner(i)}) + theta * (theta - 1.0) * "
             f"({dhorner(i)})") if m > 1 else (lambda i: f"dy[{i}] + (2.0 * theta - 1.0) * g0[{i}]")
    lines += [f"\n{ENTRY}\ndef dense_slope(cf, theta):", f"    {cf} = cf",
              "    return " + tup(slope(i) for i in range(n))]
    return "\n".join(lines) + "\n"
