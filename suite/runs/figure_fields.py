"""Field layers of a figure: a function of a problem record on a grid, without integration.

Level curves of a first integral ([HLW] Fig 1.2's exact solution curves, Fig 3.1's Hénon–Heiles
potential U = H at p = 0, [HLW] (3.2); [B] Fig 15's level sets of H_R) and the arrows of a vector
field ([HLW] Fig 1.1, first picture). :func:`parse_field` validates one
``[[figure.panels.fields]]`` table (schema in :mod:`gnibench.suite.runs.figure_spec`);
:func:`field_table` evaluates all the fields of a normalized figure into one long table,
``fields.parquet`` beside ``samples.parquet``, so the drawing reads tables only.

A ``fixed`` state is a number, or an expression in the two axis states (numbers, the axis names,
+ − * / **, parentheses), evaluated on the grid: a state on a chart of the plane rather than
constant, e.g. [B] Fig 15(b)'s level sets of H_R at I = K = 0.1 drawn through (6.2) at φ = π/2,
``x = "p2"`` (r), ``y = "q2"`` (−P), ``fixed = { p1 = 0, q1 = "0.1 / p2" }`` (q1 = I/r).

The function is evaluated by the problem's own compiled module (the integrals, ``eval_invariants``;
the vector field ``base_f``): the same code the cells use. ``function = "domain"`` (problems with
a fundamental domain, e.g. ``geodesic-genus2``'s octagon Ω of [B] §8.1, (8.3)) is min_k g_k over
the domain's sides (``Problem.boundary``, Ω = {g_k > 0}), so its level 0 (the default) draws the
boundary of the domain.
"""
from __future__ import annotations

import ast
import math

import numpy as np
from gnibench.suite.foundation.errors import UserError, unknown

FIELD_KEYS = ("problem", "function", "kind", "x", "y", "fixed", "xrange", "yrange", "n", "levels",
              "through", "label", "color")
FIELD_KINDS = ("contour", "quiver")
MAX_GRID = 1000


def parse_field(field, where: str) -> dict:
    """Validate a field table; the normalized field (levels resolved, fixed values complete)."""
    from gnibench.suite.cell.spec import parse_problem
    from gnibench.suite.metrics.base import integral_names

    if not isinstance(field, dict):
        raise UserError(f"{where}: bad value; allowed: a table")
    for key in field:
        if key not in FIELD_KEYS:
            raise UserError(f"{where}: {unknown('key', key, FIELD_KEYS)}")
    spec = field.get("problem")
    if not isinstance(spec, str):
        raise UserError(f"{where}: missing problem (a PROBLEM spec string)")
    try:
        problem = parse_problem(spec)
    except UserError as e:
        raise UserError(f"{where}: {e}") from None
    rec = problem.record
    kind = field.get("kind", "contour")
    if kind not in FIELD_KINDS:
        raise UserError(f"{where}: {unknown('kind', str(kind), FIELD_KINDS)}")
    integrals = integral_names(problem)
    function = field.get("function", "field" if kind == "quiver" else None)
    allowed = ("field",) if kind == "quiver" else tuple(integrals) + (
        ("domain",) if rec.boundary is not None else ())
    if function not in allowed:
        raise UserError(f"{where}: {unknown('function', str(function), allowed)}")
    x, y = field.get("x"), field.get("y")
    for axis, name in (("x", x), ("y", y)):
        if name not in rec.state:
            raise UserError(f"{where}: {axis}: {unknown('state', str(name), rec.state)}")
    if x == y:
        raise UserError(f"{where}: x and y are the same state {x!r}")
    y0 = dict(zip(rec.state, rec.y0(problem.values)))
    fixed = field.get("fixed", {})
    if not isinstance(fixed, dict):
        raise UserError(f"{where}: bad fixed = {fixed!r}; allowed: a table state = number")
    for name, value in fixed.items():
        if name not in rec.state or name in (x, y):
            others = [s for s in rec.state if s not in (x, y)]
            raise UserError(f"{where}: fixed: {unknown('state', name, others)}")
        y0[name] = (_expression(value, (x, y), f"{where}: fixed.{name}") if isinstance(value, str)
                    else _number(value, f"{where}: fixed.{name}"))
    out = {"problem": problem.text(), "function": function, "kind": kind, "x": x, "y": y,
           "fixed": {s: v for s, v in y0.items() if s not in (x, y)},
           "xrange": _range(field, "xrange", where), "yrange": _range(field, "yrange", where),
           "label": _line(field.get("label", ""), f"{where}: label"),
           "color": _line(field.get("color", ""), f"{where}: color")}
    n = field.get("n", 200 if kind == "contour" else 21)
    if isinstance(n, bool) or not isinstance(n, int) or not 2 <= n <= MAX_GRID:
        raise UserError(f"{where}: bad n = {n!r}; allowed: an integer from 2 to {MAX_GRID}")
    out["n"] = n
    out["levels"] = _levels(field, out, kind, where)
    return out


def _number(value, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise UserError(f"{where}: bad value {value!r}; allowed: a finite number")
    return float(value)


def _line(value, where: str) -> str:
    if not isinstance(value, str) or not value.isprintable():
        raise UserError(f"{where}: bad value {value!r}; allowed: one line of text")
    return value


_EXPR_NODES = (ast.Expression, ast.BinOp, ast.UnaryOp, ast.Constant, ast.Name, ast.Load,
               ast.Add, ast.Sub, ast.Mult, ast.Div, ast.Pow, ast.USub, ast.UAdd)


def _expression(text: str, axes: tuple, where: str) -> str:
    """A fixed state given as an expression in the axis states (checked; kept as text)."""
    try:
        tree = ast.parse(text, mode="eval")
    except SyntaxError:
        tree = None
    ok = tree is not None and all(
        isinstance(n, _EXPR_NODES)
        and (not isinstance(n, ast.Constant) or type(n.value) in (int, float))
        and (not isinstance(n, ast.Name) or n.id in axes) for n in ast.walk(tree))
    if not ok:
        raise UserError(f"{where}: bad expression {text!r}; allowed: numbers, the axis states "
                        f"{axes[0]} and {axes[1]}, + - * / ** and parentheses")
    return text


def _grid_value(value, names: dict) -> np.ndarray | float:
    """A fixed state on the grid: its number, or its expression at the grid's axis values."""
    if not isinstance(value, str):
        return value
    ops = {ast.Add: np.add, ast.Sub: np.subtract, ast.Mult: np.multiply, ast.Div: np.divide,
           ast.Pow: np.power}

    def ev(node):
        if isinstance(node, ast.Constant):
            return float(node.value)
        if isinstance(node, ast.Name):
            return names[node.id]
        if isinstance(node, ast.UnaryOp):
            return -ev(node.operand) if isinstance(node.op, ast.USub) else ev(node.operand)
        return ops[type(node.op)](ev(node.left), ev(node.right))

    with np.errstate(all="ignore"):
        return ev(ast.parse(value, mode="eval").body)


def _range(field: dict, key: str, where: str) -> list[float]:
    value = field.get(key)
    if not isinstance(value, list) or len(value) != 2:
        raise UserError(f"{where}: bad or missing {key} = {value!r}; allowed: [a, b] with a < b")
    a, b = (_number(v, f"{where}: {key}") for v in value)
    if not a < b:
        raise UserError(f"{where}: bad {key} = {value!r}; allowed: [a, b] with a < b")
    return [a, b]


def _levels(field: dict, out: dict, kind: str, where: str) -> list[float] | None:
    if kind == "quiver":
        if "levels" in field or "through" in field:
            raise UserError(f"{where}: levels and through apply to contours only")
        return None
    if out["function"] == "domain" and "levels" not in field and "through" not in field:
        return [0.0]                                   # the boundary of the domain
    if ("levels" in field) == ("through" in field):
        raise UserError(f"{where}: give levels = [numbers] or through = [[x, y], ...]")
    if "levels" in field:
        levels = field["levels"]
        if not isinstance(levels, list) or not levels:
            raise UserError(f"{where}: bad levels; allowed: a non-empty list of numbers")
        values = [_number(v, f"{where}: levels") for v in levels]
    else:
        points = field["through"]
        if not isinstance(points, list) or not points or not all(
                isinstance(p, list) and len(p) == 2 for p in points):
            raise UserError(f"{where}: bad through; allowed: a list of [x, y] points")
        pts = np.array([[_number(v, f"{where}: through") for v in p] for p in points])
        values = [float(v) for v in _evaluate_python(out, pts[:, 0], pts[:, 1])]
        if not all(math.isfinite(v) for v in values):
            raise UserError(f"{where}: through: {out['function']} is not finite at a point")
    return sorted(set(values))


def _states(field: dict, xs: np.ndarray, ys: np.ndarray) -> tuple[object, np.ndarray]:
    from gnibench.suite.cell.spec import parse_problem

    problem = parse_problem(field["problem"])
    rec = problem.record
    states = np.empty((len(xs), rec.dim))
    axes = {field["x"]: xs, field["y"]: ys}
    for j, name in enumerate(rec.state):
        states[:, j] = axes[name] if name in axes else _grid_value(field["fixed"][name], axes)
    return problem, states


def _evaluate_python(field: dict, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
    """A contour function at a few points, by the generated code run as plain Python (no
    compiling while a file is validated)."""
    from gnibench.problems.codegen import python_functions
    from gnibench.suite.metrics.base import integral_names

    problem, states = _states(field, np.asarray(xs, float), np.asarray(ys, float))
    if field["function"] == "domain":
        return _domain(problem, states)
    functions = python_functions(problem.record)
    integral = functions[f"integral_{integral_names(problem).index(field['function'])}"]
    par = problem.record.par(problem.values)
    out = []
    for s in states:
        try:
            out.append(float(integral(tuple(float(v) for v in s), par)))
        except (ValueError, ZeroDivisionError, OverflowError):
            out.append(math.nan)
    return np.array(out)


def _domain(problem, states: np.ndarray) -> np.ndarray:
    """min_k g_k(y) over the sides of the problem's fundamental domain (> 0 inside, 0 on its
    boundary), from the sympy sides of ``Problem.boundary`` (vectorized by lambdify)."""
    from types import SimpleNamespace

    import sympy as sp

    rec = problem.record
    symbols = [sp.Symbol(n) for n in rec.state + rec.model_params]
    sides = rec.boundary.sides(SimpleNamespace(**{str(s): s for s in symbols}))
    g = sp.lambdify(symbols, list(sides), "numpy")
    args = [states[:, j] for j in range(rec.dim)] + list(rec.par(problem.values))
    with np.errstate(all="ignore"):
        values = [np.broadcast_to(np.asarray(v, float), (len(states),)) for v in g(*args)]
    return np.min(values, axis=0)


def evaluate(field: dict, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
    """The field's function at the points (xs, ys): values (contour) or (rows, 2) (quiver)."""
    from gnibench.suite.cell.compiled import problem_kernel

    problem, states = _states(field, np.asarray(xs, float), np.asarray(ys, float))
    if field["function"] == "domain":
        return _domain(problem, states)
    kernel = problem_kernel(problem)
    with np.errstate(all="ignore"):
        if field["kind"] == "contour":
            return kernel.integrals(states)[:, kernel.integral_names.index(field["function"])]
        rec = problem.record
        ix, iy = rec.state.index(field["x"]), rec.state.index(field["y"])
        out = np.empty((len(states), 2))
        for k, s in enumerate(states):
            f = kernel.kernel.base_f(tuple(float(v) for v in s), kernel.par)
            out[k] = (f[ix], f[iy])
        return out


def field_table(figure: dict):
    """All the field layers of a normalized figure on their grids: one long table with columns
    ``panel``, ``field``, ``x``, ``y``, ``value`` (contour) or ``u``, ``v`` (quiver)."""
    import pandas as pd

    frames = []
    for p, panel in enumerate(figure.get("panels", [])):
        for k, field in enumerate(panel.get("fields", [])):
            gx = np.linspace(*field["xrange"], field["n"])
            gy = np.linspace(*field["yrange"], field["n"])
            X, Y = np.meshgrid(gx, gy)
            values = evaluate(field, X.ravel(), Y.ravel())
            frame = {"panel": np.int64(p), "field": np.int64(k), "x": X.ravel(), "y": Y.ravel()}
            if field["kind"] == "contour":
                frame["value"] = values
            else:
                frame["u"], frame["v"] = values[:, 0], values[:, 1]
            frames.append(pd.DataFrame(frame))
    columns = ["panel", "field", "x", "y", "value", "u", "v"]
    if not frames:
        return pd.DataFrame({c: pd.Series(dtype="float64") for c in columns})
    return pd.concat(frames, ignore_index=True).reindex(columns=columns)
