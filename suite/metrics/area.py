"""The area of a set of initial points carried by the flow: the numerical flow's against the
exact flow's ([HLW] I.1.3 "Area Preservation", Fig 1.3; I.1.1, Fig 1.1).

The exact flow of a Hamiltonian system with one degree of freedom preserves area: det φ'_t = 1
([HLW] I.1.3). So does symplectic Euler; explicit Euler does not (one step has det 1 + h² cos q
on the pendulum, [HLW] Fig 1.3). The Lotka–Volterra flow ([HLW] (1.1)) preserves the area form
du dv / (u v): in P = ln u, Q = ln v it is Hamiltonian with H = I of [HLW] (1.4)
(P' = v − 2 = −∂I/∂Q, Q' = 1 − u = ∂I/∂P), so ``log=true`` measures areas in (ln u, ln v).

An ensemble cell whose initial points lie in order on a closed curve (``sample = "circle"`` or
``"polygon"``, or a ``[cells.points]`` circle or polygon) carries that curve; at every common
sample time t the metric takes the polygon through the carried points, in order, and its area by
the shoelace formula, A = ½ |Σ_k (x_k y_{k+1} − x_{k+1} y_k)| in the coordinates ``of=x/y``
(default: the two sampled state components).

**Refinement.** The flow stretches the curve: a polygon through N carried points cuts the
stretched arcs short. The boundary is refined where it stretches: a segment whose carried chord
is longer, at some sample time, than ``stretch`` times the mean segment of the initial polygon
gets a new initial point at the midpoint of its curve parameter (on the circle or the polygon
itself), integrated like the others; ``refine`` rounds at most, at most ``max_points`` points.
The exact flow's polygon has the same points, carried by the reference solution.

Per cell (``cells.parquet``): ``area_initial`` (A at t = 0 of the refined polygon),
``area_final`` (at the last common sample), ``area_exact_final`` (the reference's polygon at that
time; NaN without a reference), ``area_change_final`` = area_final / area_initial − 1,
``area_change_max`` = max over the samples of |A(t) / A(0) − 1|, ``area_error_final`` =
area_final / area_exact_final − 1, ``area_points`` (points after refinement) and
``area_stretched`` (segments still longer than the threshold after the last round).
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from gnibench.suite.foundation.params import Param
from gnibench.suite.metrics.base import Metric


@dataclass
class CarriedSet:
    """A closed curve of initial points carried by a flow: the points' curve parameters ``s``
    (in [0, 1), increasing), the common sample ``times``, the carried ``states`` (points x times
    x N; NaN where a point has no sample), the reference's (or None), the indices of the two
    coordinates, and ``advance(s) -> (states, exact)`` that carries new points of the curve."""

    s: np.ndarray
    times: np.ndarray
    states: np.ndarray
    exact: np.ndarray | None
    coords: tuple[int, int]
    advance: Callable


def shoelace(x: np.ndarray, y: np.ndarray) -> float:
    """Area enclosed by the closed polygon through the points, in order (NaN when a vertex is
    missing)."""
    if len(x) < 3 or not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
        return math.nan
    return float(0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


def _plane(states: np.ndarray, coords, log: bool) -> tuple[np.ndarray, np.ndarray]:
    x, y = states[..., coords[0]], states[..., coords[1]]
    if log:
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.log(x), np.log(y)
    return x, y


def areas(states: np.ndarray, coords, log: bool) -> np.ndarray:
    """A(t) at every sample time (states: points x times x N)."""
    x, y = _plane(states, coords, log)
    return np.array([shoelace(x[:, j], y[:, j]) for j in range(states.shape[1])])


def stretched(states: np.ndarray, coords, log: bool, limit: float) -> np.ndarray:
    """Indices k of the segments (point k to point k+1, cyclically) longer than ``limit`` at
    some sample time."""
    x, y = _plane(states, coords, log)
    length = np.hypot(np.roll(x, -1, axis=0) - x, np.roll(y, -1, axis=0) - y)
    with np.errstate(invalid="ignore"):
        return np.flatnonzero(np.nanmax(np.where(np.isfinite(length), length, 0.0), axis=1)
                              > limit)


def carried_area(carried: CarriedSet, values: dict) -> dict:
    """The metric's values (see the module docstring) after refining the carried curve."""
    log, stretch = bool(values["log"]), float(values["stretch"])
    s, states, exact = carried.s, carried.states, carried.exact
    x0, y0 = _plane(states[:, :1], carried.coords, log)
    perimeter = float(np.sum(np.hypot(np.roll(x0, -1, axis=0) - x0, np.roll(y0, -1, axis=0) - y0)))
    limit = stretch * perimeter / len(s)
    for _ in range(int(values["refine"])):
        split = stretched(states, carried.coords, log, limit)
        room = int(values["max_points"]) - len(s)
        if not len(split) or room <= 0:
            break
        split = split[:room]
        ends = np.append(s, 1.0)
        new = 0.5 * (ends[split] + ends[split + 1])
        more, more_exact = carried.advance(new)
        at = split + 1                         # insert after each split segment's first point
        s = np.insert(s, at, new)
        states = np.insert(states, at, more, axis=0)
        if exact is not None:
            exact = np.insert(exact, at, more_exact, axis=0)
    a = areas(states, carried.coords, log)
    out = {"area_initial": a[0], "area_final": a[-1], "area_points": float(len(s)),
           "area_stretched": float(len(stretched(states, carried.coords, log, limit)))}
    with np.errstate(divide="ignore", invalid="ignore"):
        change = a / a[0] - 1.0
        out["area_change_final"] = float(change[-1])
        out["area_change_max"] = float(np.max(np.abs(np.where(np.isnan(change), np.inf, change))))
        if exact is not None:
            e = areas(exact, carried.coords, log)
            out["area_exact_final"] = e[-1]
            out["area_error_final"] = float(a[-1] / e[-1] - 1.0)
        else:
            out["area_exact_final"] = out["area_error_final"] = math.nan
    return out


def _plane_check(problem, values) -> str:
    names = values.get("of")
    if names is None:
        return ""
    state = problem.record.state
    if len(names) != 2 or any(n not in state for n in names):
        return (f"bad of={'/'.join(names)}; allowed: two state components of {problem.id} "
                f"({', '.join(state)})")
    return ""


def _not_for_one(traj, problem, values) -> str:
    return ("computed over the orbits of an ensemble cell whose initial points lie on a closed "
            "curve (sample = circle or polygon), not from one trajectory")


area = Metric(
    id="area", title="area of a set carried by the numerical flow, against the exact flow's",
    reference="[HLW] I.1.3 (area preservation), Figs 1.1 and 1.3",
    doc=("the polygon through the carried points of a closed curve of initial points (an "
         "ensemble of sample = circle or polygon), refined where the flow stretches it: its "
         "area by the shoelace formula at every common sample, against its area at t = 0 and "
         "against the exact flow's polygon of the same points (log=true: in ln x, ln y, the "
         "Lotka-Volterra area form du dv/(u v))"),
    compute=carried_area, scope="ensemble", check=_not_for_one, problem_check=_plane_check,
    params=(Param("of", None, "the two state components of the plane (default: the two sampled "
                  "ones)", kind="names"),
            Param("log", False, "areas in (ln x, ln y)", kind="bool"),
            Param("refine", 4, "rounds of refinement at most", kind="int", low=0, high=20),
            Param("stretch", 3.0, "a segment longer than this times the initial mean segment is "
                  "split", low=1.0, low_open=True),
            Param("max_points", 4096, "points of the refined curve at most", kind="int",
                  low=3, high=100_000)),
    scalars=(("area_initial", "area of the polygon at t = 0"),
             ("area_final", "its area at the last common sample"),
             ("area_exact_final", "the exact flow's polygon's area then (NaN: no reference)"),
             ("area_change_final", "area_final / area_initial - 1"),
             ("area_change_max", "max over the samples of |A(t)/A(0) - 1|"),
             ("area_error_final", "area_final / area_exact_final - 1"),
             ("area_points", "points of the refined curve"),
             ("area_stretched", "segments still longer than the threshold")),
)
