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

The keys, their types and bounds are in :mod:`gnibench.suite.runs.experiment_schema` (``ScaleTop``,
``ScaleGroup``, ``Points``, ``Circle``, ``Polygon``). The cells of a point set are numbered in the order of the points (counterclockwise for a circle,
along the vertices for a polygon), so the drawing can join them into the image of the outline.
"""
from __future__ import annotations

import copy

import numpy as np
from gnibench.suite.foundation.errors import UserError, unknown

SCALES = ("paper", "quick")


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


def at_scale(doc: dict, scale: str) -> dict:
    """The parsed file with the overrides of ``scale`` applied and every ``scale`` table removed.
    The file has been validated as a whole before (:mod:`gnibench.suite.runs.experiment_schema`:
    the overrides of every scale are checked, so a bad one is found whichever runs)."""
    check_scale(scale)
    doc = copy.deepcopy(doc)
    _override(doc, doc.pop("scale", {}).get(scale, {}))
    for group in doc.get("cells", []):
        _override(group, group.pop("scale", {}).get(scale, {}))
    return doc


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
    """The number of points of a point set (a validated ``Points`` record, or None), counted
    before its points are made."""
    if points is None:
        return 1
    if points.list_ is not None:
        return len(points.list_)
    shape = points.circle or points.polygon
    n = shape.n if shape.n is not None else points.n
    return n if n is not None else 1


def point_options(points, where: str) -> list[dict[str, float]]:
    """The problem options of each point of a validated point set, in order."""
    where = f"{where}: points"
    options = points.options
    dim = len(options)
    if points.list_ is not None:
        coords = _coords(points.list_, dim, f"{where}.list")
    else:
        shape = "circle" if points.circle is not None else "polygon"
        spec = points.circle or points.polygon
        n = spec.n if spec.n is not None else points.n
        if n is None:
            from gnibench.suite.runs.experiment_schema import MAX_POINTS

            raise UserError(f"{where}.{shape}: missing n; allowed: an integer from 3 to "
                            f"{MAX_POINTS} (in the {shape} or the point set)")
        coords = _circle(spec, n, dim, where) if shape == "circle" else _polygon(spec, n, dim,
                                                                                  where)
    return [dict(zip(options, (float(x) for x in point))) for point in coords]


def _coords(value, dim: int, where: str) -> np.ndarray:
    for k, point in enumerate(value):
        if len(point) != dim:
            raise UserError(f"{where}[{k}]: bad point {list(point)!r}; allowed: a list of {dim} "
                            f"numbers (one per option)")
    return np.array(value, dtype=float)


def _circle(spec, n: int, dim: int, where: str) -> np.ndarray:
    if dim != 2:
        raise UserError(f"{where}.circle: needs two options (got {dim})")
    angle = 2 * np.pi * np.arange(n) / n
    return np.array(spec.center) + spec.radius * np.column_stack([np.cos(angle), np.sin(angle)])


def _polygon(spec, n: int, dim: int, where: str) -> np.ndarray:
    """n points evenly spaced by arc length along the closed polygon, from its first vertex."""
    vertices = _coords(spec.vertices, dim, f"{where}.polygon.vertices")
    if len(vertices) < 3:
        raise UserError(f"{where}.polygon.vertices: needs at least 3 vertices")
    closed = np.vstack([vertices, vertices[:1]])
    edges = np.linalg.norm(np.diff(closed, axis=0), axis=1)
    if np.any(edges == 0):
        raise UserError(f"{where}.polygon.vertices: two consecutive vertices are equal")
    arc = np.concatenate([[0.0], np.cumsum(edges)])
    s = arc[-1] * np.arange(n) / n
    return np.column_stack([np.interp(s, arc, closed[:, j]) for j in range(dim)])
