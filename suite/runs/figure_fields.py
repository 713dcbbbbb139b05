"""Field layers of a figure: a function of a problem record on a grid, without integration.

Level curves of a first integral ([HLW] Fig 1.2's exact solution curves, Fig 3.1's Hénon–Heiles
potential U = H at p = 0, [HLW] (3.2); [B] Fig 15's level sets of H_R) and the arrows of a vector
field ([HLW] Fig 1.1, first picture). :func:`parse_field` checks one
``[[figure.panels.fields]]`` record (schema in :mod:`gnibench.suite.runs.figure_schema`) against
its problem;
:func:`field_table` evaluates all the fields of a normalized figure into one long table,
``fields.parquet`` beside ``samples.parquet``, so the drawing reads tables only.

A ``fixed`` state is a number, or an expression in the two axis states (numbers, the axis names,
+ − * / **, parentheses; :mod:`gnibench.suite.foundation.expressions`, bounded: ``"1/0"``,
``"1e400"`` or a 400-digit literal are refused when the file is read), evaluated on the grid: a state on a chart of the plane rather than
constant, e.g. [B] Fig 15(b)'s level sets of H_R at I = K = 0.1 drawn through (6.2) at φ = π/2,
``x = "p2"`` (r), ``y = "q2"`` (−P), ``fixed = { p1 = 0, q1 = "0.1 / p2" }`` (q1 = I/r).

The function is evaluated by the problem's own compiled module (the integrals, ``eval_invariants``;
the vector field ``base_f``): the same code the cells use. ``function = "domain"`` (problems with
a fundamental domain, e.g. ``geodesic-genus2``'s octagon Ω of [B] §8.1, (8.3)) is min_k g_k over
the domain's sides (``Problem.boundary``, Ω = {g_k > 0}), so its level 0 (the default) draws the
boundary of the domain.
"""
from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from gnibench.suite.foundation import expressions
from gnibench.suite.foundation.errors import UserError, unknown
from gnibench.suite.foundation.records import short

if TYPE_CHECKING:
    from gnibench.suite.runs.figure_schema import FieldLayer


def parse_field(field: FieldLayer | dict, where: str) -> dict:
    """Check a field record (or table) against its problem; the normalized field (levels resolved,
    fixed values complete: numbers, or checked expressions kept as text)."""
    from gnibench.suite.cell.spec import parse_problem
    from gnibench.suite.foundation.records import validate
    from gnibench.suite.metrics.base import integral_names
    from gnibench.suite.runs.figure_schema import FieldLayer

    if isinstance(field, dict):                   # a table not validated yet
        field = validate(FieldLayer, field, where)
    try:
        problem = parse_problem(field.problem)
    except UserError as e:
        raise UserError(f"{where}: {e}") from None
    rec = problem.record
    kind = field.kind
    integrals = integral_names(problem)
    function = field.function if field.function is not None else (
        "field" if kind == "quiver" else None)
    allowed = ("field",) if kind == "quiver" else tuple(integrals) + (
        ("domain",) if rec.boundary is not None else ())
    if function not in allowed:
        raise UserError(f"{where}: {unknown('function', str(function), allowed)}")
    x, y = field.x, field.y
    for axis, name in (("x", x), ("y", y)):
        if name not in rec.state:
            raise UserError(f"{where}: {axis}: {unknown('state', str(name), rec.state)}")
    if x == y:
        raise UserError(f"{where}: x and y are the same state {x!r}")
    y0 = dict(zip(rec.state, rec.y0(problem.values)))
    for name, value in field.fixed.items():
        if name not in rec.state or name in (x, y):
            others = [s for s in rec.state if s not in (x, y)]
            raise UserError(f"{where}: fixed: {unknown('state', name, others)}")
        here = f"{where}: fixed.{name}"
        if isinstance(value, str):
            expressions.parse(value, here, names=(x, y), functions=(), logic=False)
        elif isinstance(value, bool) or not isinstance(value, (int, float)) or not (
                abs(value) <= 2 ** 53 if isinstance(value, int) else math.isfinite(value)):
            raise UserError(f"{here}: bad value {short(value)}; allowed: a finite number, or an "
                            f"expression of {x} and {y} (a string)")
        y0[name] = value if isinstance(value, str) else float(value)
    out = {"problem": problem.text(), "function": function, "kind": kind, "x": x, "y": y,
           "fixed": {s: v for s, v in y0.items() if s not in (x, y)},
           "xrange": list(field.xrange), "yrange": list(field.yrange),
           "label": field.label, "color": field.color,
           "n": field.n if field.n is not None else (200 if kind == "contour" else 21)}
    out["levels"] = _levels(field, out, kind, where)
    return out


def _grid_value(value, names: dict) -> np.ndarray | float:
    """A fixed state on the grid: its number, or its expression at the grid's axis values."""
    if not isinstance(value, str):
        return value
    return expressions.evaluate_array(expressions.parse(value, "fixed", names=tuple(names),
                                                        functions=(), logic=False), names)


def _levels(field: FieldLayer, out: dict, kind: str, where: str) -> list[float] | None:
    if kind == "quiver":
        if field.levels is not None or field.through is not None:
            raise UserError(f"{where}: levels and through apply to contours only")
        return None
    if out["function"] == "domain" and field.levels is None and field.through is None:
        return [0.0]                                   # the boundary of the domain
    if (field.levels is None) == (field.through is None):
        raise UserError(f"{where}: give levels = [numbers] or through = [[x, y], ...]")
    if field.levels is not None:
        values = list(field.levels)
    else:
        pts = np.array(field.through, dtype=float)
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
