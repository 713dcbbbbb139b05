"""Two scales of one experiment file, and sets of initial points: both expand into plain cells.

**Scales.** The top-level and group values of an experiment file are the ``paper`` scale: the
seed's horizons and step sizes. A file may state a shortened ``quick`` scale (and, rarely, change
the paper one) with overrides::

    [scale.quick]                  # top level: replaces t_end | steps, every, section
    t_end = 62.8
    every = 10

    [[cells]]
    ...
    [cells.scale.quick]            # one group: t_end | steps, every, section, vary.<...>, points.<...>
    steps = 200
    vary.h = [0.01, 0.005]         # replaces vary.h only (other vary keys stay)
    points.n = 40                  # replaces n of the group's point set

A horizon given in a scale (``t_end`` or ``steps``) replaces the horizon at the same level (both
keys); ``every`` replaces ``every``; ``vary`` and ``points`` are merged key by key. A group that
states its own horizon keeps it at every scale unless its own ``[cells.scale.<name>]`` changes
it. A scale the file does not state is the paper scale.

**Point sets.** A group's ``points`` makes one cell per initial point (the flow of a set,
[HLW] Figs 1.1 and 1.3): the points set the problem options named in ``options``, in order::

    [cells.points]
    options = ["q0", "p0"]                                   # problem options, one per coordinate
    circle = { center = [0.0, 1.5], radius = 0.4, n = 60 }   # or
    polygon = { vertices = [[1, 2], [3, 2], [2, 4]], n = 90 } # evenly spaced along the outline, or
    list = [[1.0, 2.0], [1.5, 2.5]]

The cells of a point set are numbered in the order of the points (counterclockwise for a circle,
along the vertices for a polygon), so the drawing can join them into the image of the outline.
"""
from __future__ import annotations

import copy
import math

import numpy as np
from gnibench.suite.foundation.errors import UserError, unknown

SCALES = ("paper", "quick")
TOP_SCALE_KEYS = ("t_end", "steps", "every", "section")
GROUP_SCALE_KEYS = ("t_end", "steps", "every", "section", "vary", "points")
POINT_KEYS = ("options", "circle", "polygon", "list", "n")
SHAPES = ("circle", "polygon", "list")
MAX_POINTS = 10_000


def check_scale(scale: str) -> str:
    if scale not in SCALES:
        raise unknown("scale", scale, SCALES)
    return scale


def scales_stated(doc: dict) -> tuple[str, ...]:
    """The scales a parsed file states beside the paper one (at the top or in a group)."""
    named = set(doc.get("scale", {}) if isinstance(doc.get("scale"), dict) else ())
    for group in doc.get("cells", []) if isinstance(doc.get("cells"), list) else []:
        if isinstance(group, dict) and isinstance(group.get("scale"), dict):
            named |= set(group["scale"])
    return tuple(s for s in SCALES if s in named or s == "paper")


def at_scale(doc: dict, scale: str, source: str) -> dict:
    """The parsed file with the overrides of ``scale`` applied and every ``scale`` table removed
    (the overrides of the other scales are checked too, so a bad one is found whichever runs)."""
    check_scale(scale)
    doc = copy.deepcopy(doc)
    top = _scale_tables(doc.pop("scale", {}), TOP_SCALE_KEYS, f"{source}: scale")
    _override(doc, top.get(scale, {}))
    groups = doc.get("cells")
    if isinstance(groups, list):
        for gi, group in enumerate(groups):
            if not isinstance(group, dict):
                continue
            own = _scale_tables(group.pop("scale", {}), GROUP_SCALE_KEYS,
                                f"{source}: cells[{gi}].scale")
            _override(group, own.get(scale, {}))
    return doc


def _scale_tables(value, keys: tuple[str, ...], where: str) -> dict:
    if not isinstance(value, dict):
        raise UserError(f"{where}: bad value {value!r}; allowed: tables [scale.quick] or "
                        f"[scale.paper]")
    for name, table in value.items():
        if name not in SCALES:
            raise UserError(f"{where}: {unknown('scale', name, SCALES)}")
        if not isinstance(table, dict):
            raise UserError(f"{where}.{name}: bad value {table!r}; allowed: a table of "
                            f"{', '.join(keys)}")
        for key in table:
            if key not in keys:
                raise UserError(f"{where}.{name}: {unknown('key', key, keys)}")
        if "t_end" in table and "steps" in table:
            raise UserError(f"{where}.{name}: both steps and t_end given; allowed: one of them")
        for key in ("vary", "points"):
            if key in table and not isinstance(table[key], dict):
                raise UserError(f"{where}.{name}.{key}: bad value {table[key]!r}; allowed: a "
                                f"table (its keys replace those of the group's {key})")
    return value


def _override(table: dict, changes: dict) -> None:
    if "t_end" in changes or "steps" in changes:
        table.pop("t_end", None)
        table.pop("steps", None)
    for key, value in changes.items():
        if key in ("vary", "points") and isinstance(table.get(key), dict):
            merged = table[key]
            for k, v in value.items():
                if isinstance(v, dict) and isinstance(merged.get(k), dict):
                    merged[k] = {**merged[k], **v}
                else:
                    merged[k] = v
        else:
            table[key] = value


# -- point sets ------------------------------------------------------------------------------------

def planned_points(points) -> int:
    """The number of points a ``points`` table makes, counted before it is checked."""
    if not isinstance(points, dict):
        return 1
    if isinstance(points.get("list"), list):
        return len(points["list"]) or 1
    for shape in ("circle", "polygon"):
        spec = points.get(shape)
        if isinstance(spec, dict):
            n = spec.get("n", points.get("n"))
            return n if isinstance(n, int) and not isinstance(n, bool) and n > 0 else 1
    return 1


def point_options(points, where: str) -> list[dict[str, float]]:
    """The problem options of each point of a ``points`` table, in order."""
    where = f"{where}: points"
    if not isinstance(points, dict):
        raise UserError(f"{where}: bad value {points!r}; allowed: a table with options and one "
                        f"of {', '.join(SHAPES)}")
    for key in points:
        if key not in POINT_KEYS:
            raise UserError(f"{where}: {unknown('key', key, POINT_KEYS)}")
    options = points.get("options")
    if (not isinstance(options, list) or not options
            or not all(isinstance(o, str) and o for o in options) or len(set(options)) != len(options)):
        raise UserError(f"{where}: bad or missing options = {options!r}; allowed: a list of "
                        f"distinct problem option names, e.g. [\"q0\", \"p0\"]")
    shapes = [s for s in SHAPES if s in points]
    if len(shapes) != 1:
        raise UserError(f"{where}: give exactly one of {', '.join(SHAPES)} (got "
                        f"{', '.join(shapes) or 'none'})")
    shape, spec = shapes[0], points[shapes[0]]
    dim = len(options)
    if shape == "list":
        coords = _coords(spec, dim, f"{where}.list")
    else:
        if not isinstance(spec, dict):
            raise UserError(f"{where}.{shape}: bad value {spec!r}; allowed: an inline table")
        n = spec.get("n", points.get("n"))
        if isinstance(n, bool) or not isinstance(n, int) or not 3 <= n <= MAX_POINTS:
            raise UserError(f"{where}.{shape}: bad n = {n!r}; allowed: an integer from 3 to "
                            f"{MAX_POINTS}")
        coords = _circle(spec, n, dim, where) if shape == "circle" else _polygon(spec, n, dim,
                                                                                  where)
    return [dict(zip(options, (float(x) for x in point))) for point in coords]


def _number(value, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise UserError(f"{where}: bad value {value!r}; allowed: a finite number")
    return float(value)


def _coords(value, dim: int, where: str) -> np.ndarray:
    if not isinstance(value, list) or not value or len(value) > MAX_POINTS:
        raise UserError(f"{where}: bad value; allowed: a list of 1 to {MAX_POINTS} points")
    out = []
    for k, point in enumerate(value):
        if not isinstance(point, list) or len(point) != dim:
            raise UserError(f"{where}[{k}]: bad point {point!r}; allowed: a list of {dim} numbers "
                            f"(one per option)")
        out.append([_number(x, f"{where}[{k}]") for x in point])
    return np.array(out)


def _circle(spec: dict, n: int, dim: int, where: str) -> np.ndarray:
    for key in spec:
        if key not in ("center", "radius", "n"):
            raise UserError(f"{where}.circle: {unknown('key', key, ('center', 'radius', 'n'))}")
    if dim != 2:
        raise UserError(f"{where}.circle: needs two options (got {dim})")
    center = _coords([spec.get("center")], 2, f"{where}.circle.center")[0]
    radius = _number(spec.get("radius"), f"{where}.circle.radius")
    if radius <= 0:
        raise UserError(f"{where}.circle.radius: bad value {radius!r}; allowed: a number > 0")
    angle = 2 * np.pi * np.arange(n) / n
    return center + radius * np.column_stack([np.cos(angle), np.sin(angle)])


def _polygon(spec: dict, n: int, dim: int, where: str) -> np.ndarray:
    """n points evenly spaced by arc length along the closed polygon, from its first vertex."""
    for key in spec:
        if key not in ("vertices", "n"):
            raise UserError(f"{where}.polygon: {unknown('key', key, ('vertices', 'n'))}")
    vertices = _coords(spec.get("vertices"), dim, f"{where}.polygon.vertices")
    if len(vertices) < 3:
        raise UserError(f"{where}.polygon.vertices: needs at least 3 vertices")
    closed = np.vstack([vertices, vertices[:1]])
    edges = np.linalg.norm(np.diff(closed, axis=0), axis=1)
    if np.any(edges == 0):
        raise UserError(f"{where}.polygon.vertices: two consecutive vertices are equal")
    arc = np.concatenate([[0.0], np.cumsum(edges)])
    s = arc[-1] * np.arange(n) / n
    return np.column_stack([np.interp(s, arc, closed[:, j]) for j in range(dim)])
