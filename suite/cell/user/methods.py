"""``[[method]]`` entries: tableaus, compositions and Python integrators as method records.

Kinds (docs: reference, "User definitions"): ``explicit-rk`` (``c``, ``A`` lower triangle, ``b``; with
``b_hat`` and ``order_hat`` an embedded pair under the suite's step-size control), ``implicit-rk``
(``c``, full ``A``, ``b``), ``partitioned-rk`` (``u`` and ``v``, each ``{A, b, c}``, for the
blocks of the problem's partition), ``composition`` (``basis`` a registered method id, ``gamma``
the step fractions), ``python`` and ``python-solver`` (:mod:`.python_methods`).

Coefficients are numbers or expressions (``"1/(2-2^(1/3))"``), exact where rational. The declared
``order`` is checked on load by the order conditions: rooted trees in exact rational arithmetic
(:mod:`gnibench.methods.order_conditions`; irrational entries to 50 digits, within 1e-40),
bicoloured trees for partitioned tableaus (exact, or within 1e-30 for irrational entries) and for
compositions of a basis known as a tableau (:mod:`gnibench.methods.prk_conditions`; exact for
rational steps of a shipped partitioned basis, else in double precision, relative 1e-10), and for a composition of another basis the conditions of [HLW] II.4 (Σγ = 1,
Σγ^(p+1) = 0; order p + 2 for a symmetric basis and symmetric γ). A failing condition refuses the
entry and is named. The kernels are generated as for the shipped methods.
"""
from __future__ import annotations

import json
from dataclasses import dataclass, replace
from fractions import Fraction
from pathlib import Path

from gnibench.methods.base import H_PARAM, NEWTON_PARAMS, Method
from gnibench.methods.tableau import TableauShape
from gnibench.suite.cell.user.entries import Entry
from gnibench.suite.cell.user.precision import _float_rk_check, printed_digits, printed_rtol
from gnibench.suite.cell.user.properties import check_declared, tolerance
from gnibench.suite.foundation.params import Param

KINDS = ("explicit-rk", "implicit-rk", "partitioned-rk", "composition", "python", "python-solver")
COMMON = ("id", "kind", "title", "reference", "order", "symplectic", "symmetric")
KEYS = {"explicit-rk": ("c", "A", "b", "b_hat", "order_hat"), "implicit-rk": ("c", "A", "b"),
        "partitioned-rk": ("u", "v"), "composition": ("basis", "gamma"), "python": ("entry",),
        "python-solver": ("entry", "rtol", "atol")}
TOL_DIGITS = 50


@dataclass(frozen=True)
class Tab(TableauShape):
    """A tableau as the kernel generators read it (entries: nearest doubles, as Fractions)."""

    a: tuple
    b: tuple
    c: tuple
    order: int

    @property
    def doubles(self) -> tuple[tuple[tuple[float, ...], ...], tuple[float, ...]]:
        """(A, b) as the kernels use them (methods/tableau.py ``Tableau.doubles``): the entries
        are already the nearest doubles."""
        return tuple(tuple(float(x) for x in row) for row in self.a), tuple(float(x) for x in self.b)


def build_method(e: Entry, origin, known) -> Method:
    """The method record of one entry; ``known(id)`` finds a basis (registered, or defined
    earlier in the same file)."""
    kind = e.table.get("kind")
    if kind not in KINDS:
        raise e.error("kind", f"bad value {kind!r}; allowed: {', '.join(KINDS)}")
    e.keys(COMMON + KEYS[kind])
    mid = e.ident()
    python = kind.startswith("python")
    order = e.integer("order", 0 if python else 1, 12, required=not python) or 0
    info = {"id": mid, "order": order,
            "reference": e.text("reference", f"user definition ({e.source})"),
            "doc": e.text("title", f"user {kind} method"), "symplectic": e.flag("symplectic"),
            "symmetric": e.flag("symmetric"), "origin": origin}
    definition = {"source": e.source, "entry": e.table}
    if python:
        method = _python(e, kind, info, definition)
    elif kind == "composition":
        method = _composition(e, info, known, definition)
    elif kind == "partitioned-rk":
        method = _partitioned(e, info, order)
    else:
        method = _runge_kutta(e, kind, info, order)
    return replace(method, definition=json.dumps(definition, sort_keys=True, default=str))


# -- coefficients -------------------------------------------------------------------------------

def _numbers(e: Entry, key: str, value, length: int | None = None) -> tuple[list, list, bool]:
    """(exact values for the order conditions, nearest doubles as Fractions, all rational?)."""
    import sympy as sp

    if not isinstance(value, list) or not value or (length is not None and len(value) != length):
        want = f"{length} " if length is not None else ""
        raise e.error(key, f"bad value {value!r}; allowed: a list of {want}numbers or expressions")
    exact, near, rational = [], [], True
    for k, x in enumerate(value):
        v = e.constant(f"{key}[{k}]", x)
        if isinstance(v, sp.Rational):
            exact.append(Fraction(int(v.p), int(v.q)))
            near.append(Fraction(float(v)))
        else:
            rational = False
            exact.append(Fraction(str(v.evalf(TOL_DIGITS))))
            near.append(Fraction(float(v.evalf(30))))
    return exact, near, rational


def _matrix(e: Entry, key: str, value, s: int, lower: bool) -> tuple[list, list, bool]:
    if not isinstance(value, list) or len(value) != s:
        raise e.error(key, f"bad value: {s} rows expected (one per stage)")
    exact, near, rational = [], [], True
    for i, row in enumerate(value):
        if lower and isinstance(row, list) and len(row) == i:
            row = row + [0] * (s - i)                    # the strictly lower part of row i
        if i == 0 and lower and row == []:
            row = [0] * s
        x, n, r = _numbers(e, f"{key}[{i}]", row, s)
        if lower and any(x[j] != 0 for j in range(i, s)):
            raise e.error(key, f"row {i + 1} has entries on or above the diagonal; an explicit "
                               f"method's A is strictly lower triangular")
        exact.append(x)
        near.append(n)
        rational = rational and r
    return exact, near, rational


def _tableau(e: Entry, table: dict, prefix: str, lower: bool):
    """(exact (A, b, c), kernel Tab-parts, rational?) of a table with keys A, b, c."""
    b, b_near, rb = _numbers(e, f"{prefix}b", table.get("b"))
    s = len(b)
    c, c_near, rc = _numbers(e, f"{prefix}c", table.get("c"), s)
    a, a_near, ra = _matrix(e, f"{prefix}A", table.get("A"), s, lower)
    return (a, b, c), (a_near, b_near, c_near), rb and rc and ra


def _require(e: Entry, key: str, failures: list, what: str) -> None:
    if failures:
        more = f" (and {len(failures) - 1} more)" if len(failures) > 1 else ""
        raise e.error(key, f"{what}: {failures[0]}{more}")


def _check_rk(e: Entry, exact, rational: bool, order: int, key: str, c=True,
              digits: int = 0) -> None:
    from gnibench.methods.order_conditions import check

    a, b, cc = exact
    tol = 0 if rational else Fraction(1, 10 ** 40)
    rtol = printed_rtol(digits)
    if rtol is None:
        failures = check(a, b, cc if c else None, order, tol)
    else:                               # printed decimals: to their precision, in doubles
        failures = _float_rk_check(a, b, cc if c else None, order, rtol)
    if failures and failures[0].order == 0:                     # a row of A does not sum to c
        _require(e, "c", failures, "the rows of A must sum to c")
    _require(e, key, failures, f"the tableau does not have the declared {key.replace('_', ' ')} "
                               f"{order}")


# -- the kinds ----------------------------------------------------------------------------------

def _runge_kutta(e: Entry, kind: str, info: dict, order: int) -> Method:
    from gnibench.methods import embedded_rk
    from gnibench.methods.assembly.steps.erk import write_erk
    from gnibench.methods.assembly.steps.irk import write_irk
    from gnibench.methods.assembly.steps.prk import write_prk
    from gnibench.methods.implicit_rk import _d_coefficients

    explicit = kind == "explicit-rk"
    exact, (a, b, c), rational = _tableau(e, e.table, "", lower=explicit)
    digits = printed_digits([e.table.get(k) for k in ("A", "b", "c")])
    _check_rk(e, exact, rational, order, "order", digits=digits)
    check_declared(e, info, exact[:2], None, exact[2],
                   tolerance(rational, printed_rtol(digits), [*exact[1], *(x for row in exact[0] for x in row)]))
    tab = Tab(tuple(map(tuple, a)), tuple(b), tuple(c), order)
    if explicit and "b_hat" in e.table:
        bh_exact, bh, r = _numbers(e, "b_hat", e.table["b_hat"], len(b))
        order_hat = e.integer("order_hat", 1, 12)
        _check_rk(e, (exact[0], bh_exact, exact[2]), rational and r, order_hat, "order_hat",
                  c=False, digits=max(digits, printed_digits(e.table["b_hat"])))
        pair = embedded_rk.Pair(tab=tab, e=tuple(x - y for x, y in zip(b, bh)),
                                iord=max(order, order_hat), expo=1.0 / (min(order, order_hat) + 1))
        method = embedded_rk.embedded(info["id"], pair, order, info["reference"], info["doc"])
        return replace(method, **{k: v for k, v in info.items() if k not in ("reference", "doc")})
    if "order_hat" in e.table:
        raise e.error("order_hat", "applies only with b_hat (an embedded pair)")
    if explicit:
        return Method(family="explicit-rk", generate=write_erk(tab), data=tab, **info)
    try:
        generate = write_irk(tab, _d_coefficients(tab))  # A invertible: y1 from the stages
    except (StopIteration, ZeroDivisionError):
        generate = write_prk((a, b))               # singular A (Lobatto IIIA): b from f(Y_j)
    return Method(family="implicit-rk", generate=generate, data=tab, implicit=True,
                  params=(H_PARAM,) + NEWTON_PARAMS, **info)


def _partitioned(e: Entry, info: dict, order: int) -> Method:
    from gnibench.methods import prk_conditions
    from gnibench.methods.assembly.steps.prk import stage_order, write_prk

    forms, kernel, rational, cs = [], [], True, []
    for block in ("u", "v"):
        table = e.table.get(block)
        if not isinstance(table, dict):
            raise e.error(block, "missing or not a table {A = [...], b = [...], c = [...]}")
        bad = set(table) - {"A", "b", "c"}
        if bad:
            raise e.error(f"{block}.{min(bad)}", "unknown key; allowed: A, b, c")
        exact, near, r = _tableau(e, table, f"{block}.", lower=False)
        forms.append((exact[0], exact[1]))
        cs.append(exact[2])
        kernel.append((near[0], near[1]))
        rational = rational and r
        _require(e, f"{block}.c", _row_sums(exact, printed_rtol(printed_digits(table))),
                 "the rows of A do not sum to c")
    if len(forms[0][1]) != len(forms[1][1]):
        raise e.error("v", "the two tableaus need the same number of stages")
    rtol = printed_rtol(printed_digits([e.table.get("u"), e.table.get("v")]))
    if rtol is None:
        failures = prk_conditions.check(forms[0], forms[1], order, None,
                                        0 if rational else Fraction(1, 10 ** 40))
    else:                               # printed decimals: to their precision, in doubles
        failures = prk_conditions.check(*[([[float(x) for x in row] for row in a],
                                           [float(x) for x in b]) for a, b in forms], order, rtol)
    _require(e, "order", failures,
             f"the partitioned tableau does not have the declared order {order}")
    check_declared(e, info, forms[0], forms[1], cs[0],
                   tolerance(rational, rtol, [x for a, b in forms for x in (*b, *(y for row in a for y in row))]))
    (au, bu), (av, bv) = kernel
    explicit = stage_order(au, av, bu, bv, True, True) is not None
    return Method(family="partitioned-rk", generate=write_prk(kernel[0], kernel[1]),
                  data=tuple(forms), needs=("partition",), implicit=True,
                  explicit_when="separable" if explicit else "",
                  params=(H_PARAM,) + NEWTON_PARAMS, **info)


def _row_sums(exact, rtol: float | None = None) -> list[str]:
    a, _, c = exact

    def off(row, ci) -> bool:
        if rtol is None:
            return abs(sum(row) - ci) > Fraction(1, 10 ** 40)
        return abs(float(sum(row) - ci)) > rtol * float(sum(abs(x) for x in row) + abs(ci))
    return [f"row {i + 1}: Σ_j a_{i + 1}j = {sum(row)} ≠ c_{i + 1} = {c[i]}" for i, row in
            enumerate(a) if off(row, c[i])]


def forms_of(method: Method):
    """A method as a partitioned tableau ((A, b), (Â, b̂)), exactly, or None (no tableau)."""
    from gnibench.methods.prk import PRK_FORMS

    if method.id in PRK_FORMS and method.origin is None:
        return PRK_FORMS[method.id]
    data = method.data
    if method.family == "partitioned-rk" and isinstance(data, tuple):
        return data
    if method.family == "composition" and isinstance(data, dict):
        return data.get("forms")
    tab = getattr(data, "tab", data)
    if hasattr(tab, "a") and hasattr(tab, "b"):
        return (tab.a, tab.b), (tab.a, tab.b)
    return None


def _composition(e: Entry, info: dict, known, definition: dict) -> Method:
    import sympy as sp
    from gnibench.methods import METHODS, prk_conditions
    from gnibench.methods.assembly.steps.partitioned import composed_step
    from gnibench.methods.assembly.steps.prk import write_composition
    from gnibench.methods.compositions import runtime_data
    from gnibench.methods.prk import PRK_FORMS, CompositionMethod, compose

    basis_id = e.text("basis")
    basis = known(basis_id)
    if basis is None:
        raise e.error("basis", f"unknown method {basis_id!r}; allowed: a registered method id "
                               f"(or one defined above in the same file)")
    if basis.kind != "compiled" or "h" not in {p.name for p in basis.params}:
        raise e.error("basis", f"{basis_id} is not a compiled fixed-step method (kind "
                               f"{basis.kind}); allowed: a method with a step size h")
    gammas = [e.constant(f"gamma[{k}]", g) for k, g in enumerate(_list(e, "gamma"))]
    rational = all(isinstance(g, sp.Rational) for g in gammas)
    order, p = info["order"], basis.order
    forms = forms_of(basis)
    symmetric = basis.symmetric and all(sp.simplify(x - y) == 0
                                        for x, y in zip(gammas, reversed(gammas)))
    composed = None
    rtol = printed_rtol(printed_digits(e.table.get("gamma")))
    if forms is not None:
        g = [Fraction(int(x.p), int(x.q)) for x in gammas] if rational and rtol is None else \
            [float(x.evalf(30)) for x in gammas]
        composed = compose(forms, g)
        exact = rational and rtol is None and basis.id in PRK_FORMS and basis.origin is None
        _require(e, "order", prk_conditions.check(composed[0], composed[1], order,
                                                  None if exact else rtol or 1e-10),
                 f"the composition does not have the declared order {order}")
    else:
        top = p + 2 if symmetric else p + 1
        if order > top:
            raise e.error("order", f"{basis_id} has no tableau, so only the conditions of [HLW] "
                                   f"II.4 apply: at most order {top} from a basis of order {p}")
        total, tol = sum(gammas), max(rtol or 0, 1e-30)
        if abs(float((total - 1).evalf(TOL_DIGITS))) > tol:
            raise e.error("gamma", f"Σγ = {float(total.evalf(20))!r} ≠ 1 (consistency)")
        scale = float(sum(abs(x) ** (p + 1) for x in gammas).evalf(TOL_DIGITS))
        if order > p and abs(float(sum(x ** (p + 1) for x in gammas).evalf(TOL_DIGITS))) > \
                tol * scale:
            raise e.error("order", f"order {p + 1} needs Σγ^{p + 1} = 0 ([HLW] II.4, Thm 4.1)")
    if info["symplectic"] and not basis.symplectic:
        raise e.error("symplectic", f"declared true, but the basis {basis_id} is not symplectic "
                                    f"(a composition of symplectic maps is, [HLW] VI.2)")
    if info["symmetric"] and not symmetric:
        raise e.error("symmetric", f"declared true, but a composition is symmetric with a "
                                   f"symmetric basis and γ_i = γ_(s+1-i) ([HLW] V.3.1); here "
                                   f"{'γ is not' if basis.symmetric else basis_id + ' is not'}")
    if basis.definition:
        definition["basis"] = json.loads(basis.definition)
    newton = tuple(x for x in basis.params if x.name == "newton_maxit")
    floats = tuple(float(x.evalf(30)) for x in gammas)
    generate, data = write_composition(basis, floats), basis.runtime_data
    if basis is METHODS.get("stormer-verlet"):    # the shipped compositions' kernel, γ in par
        generate, data = composed_step, runtime_data(floats)
    return CompositionMethod(
        family="composition", generate=generate,
        params=(H_PARAM,) + newton, needs=basis.needs, implicit=basis.implicit,
        explicit_when=basis.explicit_when, field_modifiers_refused=basis.field_modifiers_refused,
        data={"gamma": floats, "basis": basis_id, "forms": composed}, basis=basis,
        runtime_data=data,          # (a shipped composition as basis reads its own from par)
        **{**info, "symplectic": basis.symplectic, "symmetric": symmetric})


def _list(e: Entry, key: str) -> list:
    value = e.table.get(key)
    if not isinstance(value, list) or not value:
        raise e.error(key, f"bad value {value!r}; allowed: a non-empty list")
    return value


def _python(e: Entry, kind: str, info: dict, definition: dict) -> Method:
    from gnibench.methods.external import DT_OUT
    from gnibench.suite.cell.user.python_methods import PythonMethod, entry_code, solver, stepper

    entry = e.text("entry")
    base = str(Path(e.source).resolve().parent) if Path(e.source).is_file() else ""
    try:
        _, code = entry_code(entry, base)
    except Exception as ex:  # noqa: BLE001 - any failure to import the user's code
        raise e.error("entry", f"cannot load {entry!r}: {type(ex).__name__}: {ex}") from None
    definition["code"] = code                   # the module's source: part of a cell's key
    if kind == "python":
        return PythonMethod(family="python", generate=_not_compiled, params=(H_PARAM,),
                            run=stepper(entry, base, code), kind="python", engine="python",
                            entry=entry, **info)
    tols = []
    for name in ("rtol", "atol"):
        default = e.table.get(name, 1e-6)
        if isinstance(default, bool) or not isinstance(default, (int, float)) or not default > 0:
            raise e.error(name, f"bad value {default!r}; allowed: a number > 0")
        tols.append(Param(name, float(default), f"{name[0]}-tolerance passed to the solver",
                          low=0.0, low_open=True))
    return PythonMethod(family="python", generate=_not_compiled, params=(DT_OUT, *tols),
                        run=solver(entry, base, code), kind="python", engine="python", adaptive=True,
                        grid_param="dt_out", entry=entry, **info)


def _not_compiled(ctx) -> str:
    raise RuntimeError("Python methods run through Method.run, not through compiled kernels")
