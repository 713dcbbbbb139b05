"""sympy -> numba source for a problem: the single symbolic source made into compiled scalar code.

The generated text defines, with the state ``y`` a tuple of N floats and ``par`` a tuple of floats:

* ``base_f(y, par) -> tuple``            the vector field F, [B] (2.1);
* ``base_jac(y, par, J)``               fills J (N x N array) with dF/dy, for Newton;
* ``integral_<k>(y, par) -> float``     each first integral H_k;
* ``grad_<k>(y, par) -> tuple``         its gradient, row k of D_H ([B] §2);
* ``invariants(y, par) -> tuple``       all integrals;
* ``section_g_<j>``, ``section_grad_<j>``, ``section_cond_<j>`` (y, par): g, grad g and the crossing
  condition of the problem's j-th Poincaré section (:mod:`gnibench.suite.cell.sections`).

Every function is decorated ``@shared`` (methods/assembly/source.py: cached by numba, and written
into its compiled callers by numba's inliner). The text and a small JSON of metadata are cached on
disk, keyed by the hash of the sources that produce them, so that a warm run never imports sympy.
"""
from __future__ import annotations

import cmath
import hashlib
import inspect
import json
import math
import sys
from types import SimpleNamespace

from gnibench.suite.foundation.cache import cache_dir, read_checked, write_checked


def _source_hash(problem) -> str:
    mod = sys.modules[problem.model.__module__]
    h = hashlib.sha256()
    for obj in (mod, sys.modules[__name__], sys.modules["gnibench.problems.base"]):
        h.update(inspect.getsource(obj).encode())
    h.update(problem.id.encode())
    h.update(problem.definition.encode())        # a user definition's text ("" if shipped)
    return h.hexdigest()[:16]


def problem_code(problem) -> tuple[str, dict]:
    """Return (source text, metadata) for a problem, from the disk cache or freshly from sympy."""
    memo = _memo.get(id(problem))
    if memo is not None and memo[0] is problem:
        return memo[1], memo[2]
    key = _source_hash(problem)
    d = cache_dir("problems")
    path = d / f"{problem.id}-{key}.code.json"
    doc = read_checked(path, "problem code", parse=_parse_code)
    if doc is None:
        text, meta = _generate(problem)
        write_checked(path, json.dumps({"text": text, "meta": meta}))
    else:
        text, meta = doc["text"], doc["meta"]
    _memo[id(problem)] = (problem, text, meta)
    return text, meta


_memo: dict[int, tuple] = {}


def _parse_code(raw: bytes) -> dict:
    """A cached entry as written by problem_code (anything else raises: it is rebuilt)."""
    doc = json.loads(raw)
    if not (isinstance(doc, dict) and isinstance(doc.get("text"), str)
            and isinstance(doc.get("meta"), dict)):
        raise TypeError("not a problem code entry")
    return doc


def problem_meta(problem) -> dict:
    return problem_code(problem)[1]


def symbolic(problem):
    """The sympy view of a problem: (state symbols, param symbols, rhs list, {name: integral})."""
    import sympy as sp

    ys = [sp.Symbol(f"y_{s}", real=True) for s in problem.state]
    ps = [sp.Symbol(f"c_{p}", real=True) for p in problem.model_params]
    ns = SimpleNamespace(**{s: y for s, y in zip(problem.state, ys)},
                         **{p: c for p, c in zip(problem.model_params, ps)})
    model = problem.model(ns)
    if model.hamiltonian is not None:
        # [HLW] (1.10): p' = -H_q, q' = H_p.
        pn, qn = problem.canonical
        H = model.hamiltonian
        deriv = {}
        for p, q in zip(pn, qn):
            deriv[p] = -sp.diff(H, getattr(ns, q))
            deriv[q] = sp.diff(H, getattr(ns, p))
        rhs = [deriv[s] for s in problem.state]
    else:
        rhs = list(model.rhs)
    return ys, ps, rhs, dict(model.integrals)


def vanishes(x, symbols) -> bool:
    """Whether the sympy expression ``x`` of ``symbols`` is identically zero. A value at a generic
    point that is far from zero (50 digits, against the size of its terms) proves it is not, at
    once; otherwise sympy's ``simplify`` decides. (``simplify`` alone expands powers: on a user's
    (q + p + 1)^1000 it runs for hours.)"""
    import sympy as sp

    if x == 0:
        return True
    point = {s: sp.Rational(k + 7, 10 * k + 13) for k, s in enumerate(symbols)}  # in (0, 1)
    try:
        value = complex(x.evalf(50, subs=point))
        size = sum(abs(complex(t.evalf(50, subs=point))) for t in sp.Add.make_args(x))
    except (TypeError, ValueError, ArithmeticError):
        value, size = 0j, 0.0
    if cmath.isfinite(value) and math.isfinite(size) and abs(value) > 1e-30 * size:
        return False
    return sp.simplify(x) == 0


def _generate(problem) -> tuple[str, dict]:
    import sympy as sp

    ys, ps, rhs, integrals = symbolic(problem)
    n = len(ys)
    if len(rhs) != n:
        raise ValueError(f"{problem.id}: rhs has {len(rhs)} components for {n} states")
    names = list(integrals)
    jac = sp.Matrix(rhs).jacobian(ys)
    out = [f"# problem {problem.id}: generated from its sympy definition by problems/codegen.py"]
    out += _function("base_f", ys, ps, rhs, kind="tuple")
    out += _function("base_jac", ys, ps, list(jac), kind="matrix", shape=(n, n))
    for k, name in enumerate(names):
        H = integrals[name]
        grad = [sp.diff(H, y) for y in ys]
        out += _function(f"integral_{k}", ys, ps, [H], kind="scalar", comment=name)
        out += _function(f"grad_{k}", ys, ps, grad, kind="tuple", comment=f"gradient of {name}")
    # Poincaré sections (problems.base.Section): g_j, its gradient and the direction condition
    ns = SimpleNamespace(**{s: y for s, y in zip(problem.state, ys)},
                         **{p: c for p, c in zip(problem.model_params, ps)})
    for j, sec in enumerate(problem.sections):
        g, cond = sp.sympify(sec.g(ns)), sp.sympify(sec.condition(ns))
        out += _function(f"section_g_{j}", ys, ps, [g], kind="scalar", comment=f"section {sec.name}")
        out += _function(f"section_grad_{j}", ys, ps, [sp.diff(g, y) for y in ys], kind="tuple",
                         comment=f"gradient of g of section {sec.name}")
        out += _function(f"section_cond_{j}", ys, ps, [cond], kind="scalar",
                         comment=f"crossing condition (> 0) of section {sec.name}")
    calls = ", ".join(f"integral_{k}(y, par)" for k in range(len(names)))
    out += ["", "@shared", "def invariants(y, par):",
            f"    return ({calls}{',' if len(names) == 1 else ''})"]
    meta = {"n": n, "integrals": names, "explicit_u": False, "explicit_v": False,
            "u_idx": [], "v_idx": []}
    if problem.partition is not None:
        u, v = problem.partition
        ui = [problem.state.index(s) for s in u]
        vi = [problem.state.index(s) for s in v]
        meta["u_idx"], meta["v_idx"] = ui, vi
        # [HLW] (1.9): symplectic Euler is explicit when a = F_u does not depend on u (and its
        # adjoint when b = F_v does not depend on v); true for separable H = T(p) + V(q).
        meta["explicit_u"] = all(vanishes(jac[i, j], ys + ps) for i in ui for j in ui)
        meta["explicit_v"] = all(vanishes(jac[i, j], ys + ps) for i in vi for j in vi)
    out += _partial_functions(problem, ys, ps, meta)
    return "\n".join(out) + "\n", meta


def _partial_functions(problem, ys, ps, meta) -> list[str]:
    """q-partial first integrals [B] (2.12), D_H F = L H (only for problems that declare them).

    Generates ``partial_<k>(y, par)`` (h_k), ``pgrad_<k>(y, par)`` (row k of D_H) and
    ``pl_<k>(y, par)`` (row k of L, over all partial integrals); meta gets ``partial_integrals``
    (names) and ``partial_L_nonzero`` (structure of L, to check that an observed subset is closed).
    """
    import sympy as sp

    ns = SimpleNamespace(**{s: y for s, y in zip(problem.state, ys)},
                         **{p: c for p, c in zip(problem.model_params, ps)})
    partials = dict(problem.model(ns).partial_integrals)
    if not partials:
        return []
    names = list(partials)
    out, nonzero = [], []
    for k, name in enumerate(names):
        h, lrow = partials[name]
        row = ([lrow.get(m, 0) for m in names] if isinstance(lrow, dict)
               else [lrow if m == name else 0 for m in names])
        row = [sp.sympify(x) for x in row]
        nonzero.append([not (x.is_number and x == 0) for x in row])
        out += _function(f"partial_{k}", ys, ps, [h], kind="scalar", comment=f"partial {name}")
        out += _function(f"pgrad_{k}", ys, ps, [sp.diff(h, y) for y in ys], kind="tuple",
                         comment=f"gradient of {name}")
        out += _function(f"pl_{k}", ys, ps, row, kind="tuple", comment=f"row {name} of L")
    meta["partial_integrals"], meta["partial_L_nonzero"] = names, nonzero
    return out


def _printer():
    from sympy import Rational
    from sympy.printing.pycode import PythonCodePrinter

    class Printer(PythonCodePrinter):
        """Python printer that writes x**(k/2) with math.sqrt (numba's pow is slow)."""

        def _print_Pow(self, expr, rational=False):
            b, e = expr.as_base_exp()
            if isinstance(e, Rational) and e.q == 2 and abs(e.p) > 1:
                base = self.parenthesize(b, 100)
                whole = abs(e.p) // 2
                power = base if whole == 1 else f"{base}**{whole}"
                term = f"({power}*math.sqrt({base}))"
                return f"(1.0/{term})" if e.p < 0 else term
            if e.is_Integer and e < 0:
                return f"(1.0/({self.parenthesize(b, 100)}**{-int(e)}))"
            return super()._print_Pow(expr, rational=rational)

    return Printer({"fully_qualified_modules": True, "standard": "python3"})


def _cse_steps(kind: str):
    """sympy's cse preprocessing: its "basic" steps (signs canonical, then ``factor_terms``) for
    the field, the integrals and the sections; the Jacobian without ``factor_terms``, which took
    2.0 of the 4.6 s the outer solar system's code costs (its 1296 entries) and leaves it with 380
    multiplications instead of 705 and 36 divisions instead of 51 (measured 2026-11-28)."""
    from sympy.simplify import cse_opts

    return [(cse_opts.sub_pre, cse_opts.sub_post)] if kind == "matrix" else "basic"


def _function(name, ys, ps, exprs, kind, shape=None, comment=None):
    import sympy as sp

    printer = _printer()
    subs, reduced = sp.cse(exprs, symbols=sp.numbered_symbols("t_"),
                           optimizations=_cse_steps(kind))
    args = "y, par, M" if kind == "matrix" else "y, par"
    lines = ["", "@shared", f"def {name}({args}):"]
    if comment:
        lines.append(f"    # {comment}")
    used = set().union(*[e.free_symbols for e in exprs]) if exprs else set()
    used |= set().union(*[e.free_symbols for _, e in subs]) if subs else set()
    lines.append(f"    {', '.join(str(y) for y in ys)}{',' if len(ys) == 1 else ''} = y")
    for i, c in enumerate(ps):
        if c in used:
            lines.append(f"    {c} = par[{i}]")
    for s, e in subs:
        lines.append(f"    {s} = {printer.doprint(e)}")
    if kind == "scalar":
        lines.append(f"    return {_num(printer, reduced[0])}")
    elif kind == "tuple":
        body = ", ".join(_num(printer, e) for e in reduced)
        lines.append(f"    return ({body}{',' if len(reduced) == 1 else ''})")
    else:  # zero-fill once, then only the structurally non-zero entries (N=36: compile 19 s -> 4 s)
        n, m = shape
        lines.append("    M[:, :] = 0.0")
        for i in range(n):
            for j in range(m):
                e = reduced[i * m + j]
                if not (e.is_number and e == 0):
                    lines.append(f"    M[{i}, {j}] = {_num(printer, e)}")
    return lines


def _num(printer, e) -> str:
    """Print an expression; plain numbers become float literals so the types stay float64."""
    text = printer.doprint(e)
    if e.is_number:
        return repr(float(e))
    return text


_python: dict[str, dict] = {}


def python_functions(problem) -> dict:
    """The generated functions as plain Python (no numba): for checks made before compiling."""
    text, _ = problem_code(problem)
    if text not in _python:
        import math

        namespace = {"math": math, "shared": lambda fn: fn, "internal": lambda fn: fn}
        exec(compile(text, f"<{problem.id} python>", "exec"), namespace)  # noqa: S102 - our codegen
        _python[text] = namespace
    return _python[text]
