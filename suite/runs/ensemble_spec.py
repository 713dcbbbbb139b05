"""An ensemble cell's initial conditions: made once where the experiment is read, then carried by
the cell (:class:`EnsembleSpec`), cut into units of work of a fixed number of orbits.

A group's ``[cells.ensemble]`` (or its ``[cells.points]``, an ensemble of a closed curve or a list
whose orbits' samples are all kept) makes one cell per problem x method x vary value, whose
initial conditions are the ensemble's points (:mod:`gnibench.suite.runs.sampling`). The points
are drawn once, in the process that reads the experiment, and travel with the cell: which worker
runs which orbits never changes a bit. A cell of N orbits is run as ceil(N / chunk) units of
``chunk`` orbits each (default :data:`CHUNK`), stored as one part each; the chunk is a key of the
experiment, never the number of workers, so the units are the same whatever runs them.
"""
from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, replace

import numpy as np
from gnibench.suite.foundation.errors import UserError

CHUNK = 250               # orbits per unit of work (ensemble.chunk)


@dataclass(frozen=True, eq=False)
class EnsembleSpec:
    """The initial conditions of an ensemble cell, or of one unit of it.

    Attributes
    ----------
    options:
        The sampled initial-value options (``<state>0``), one per column of ``points``.
    sample:
        box, shell, list, circle or polygon (:mod:`gnibench.suite.runs.sampling`).
    points:
        The options' values, one row per orbit (this unit's rows only).
    keep:
        Global indices of the orbits whose samples go to ``samples.parquet`` (sorted).
    chunk, first, total:
        Orbits per unit; the global index of ``points[0]``; the orbits of the whole ensemble.
    curve:
        For circle and polygon: how to make more points of the curve (the area metric refines a
        stretched boundary, :mod:`gnibench.suite.metrics.area`): ("circle", center, radius) or
        ("polygon", vertices).
    seed:
        The seed of box and shell (None for the others).
    """

    options: tuple[str, ...]
    sample: str
    points: np.ndarray
    keep: tuple[int, ...]
    chunk: int = CHUNK
    first: int = 0
    total: int = 0
    curve: tuple | None = None
    seed: int | None = None

    @property
    def n(self) -> int:
        """Orbits of this unit."""
        return len(self.points)

    def units(self, whole: bool = False) -> list[EnsembleSpec]:
        """The units of work of the whole ensemble: chunks of ``chunk`` orbits (one unit with
        ``whole``: a metric of the whole set, the area of a carried curve)."""
        size = self.total if whole else self.chunk
        return [replace(self, points=self.points[a:a + size], first=a)
                for a in range(0, self.total, size)]

    def kept(self) -> list[int]:
        """Local indices (in this unit) of the orbits whose samples are kept."""
        return [k - self.first for k in self.keep if self.first <= k < self.first + self.n]

    def digest(self) -> str:
        """What determines this unit's numbers beside the cell's specs (part of its key)."""
        h = hashlib.sha256(json.dumps([self.options, self.sample, self.kept(), self.first,
                                       self.total, self.chunk, self.curve]).encode())
        h.update(np.ascontiguousarray(self.points, dtype="<f8").tobytes())
        return h.hexdigest()

    def describe(self) -> dict:
        """What the tables' metadata records of it (not the points: ensemble.parquet has them)."""
        return {"options": list(self.options), "sample": self.sample, "orbits": self.total,
                "seed": self.seed, "chunk": self.chunk, "kept": len(self.keep)}


def from_points(points, where: str) -> dict:
    """A ``[cells.points]`` record as the keys of an ensemble: the same points, every orbit's
    samples kept."""
    shape = "list" if points.list_ is not None else "circle" if points.circle else "polygon"
    keys = {"options": list(points.options), "sample": shape, "keep": "all", "chunk": None,
            "seed": None}
    if shape == "list":
        keys["points"] = points.list_
    else:
        spec = points.circle or points.polygon
        n = spec.n if spec.n is not None else points.n
        if n is None:
            from gnibench.suite.runs.experiment_schema import MAX_POINTS

            raise UserError(f"{where}.{shape}: missing n; allowed: an integer from 3 to "
                            f"{MAX_POINTS} (in the {shape} or the point set)")
        keys["n"] = n
        if shape == "circle":
            keys.update(center=spec.center, radius=spec.radius)
        else:
            keys["vertices"] = spec.vertices
    return keys


def make(keys: dict, problem, where: str) -> EnsembleSpec:
    """The ensemble of a group for one problem (a parsed problem: the sampled options must be its
    initial values; a shell needs its integrals): keys of ``Ensemble`` (or :func:`from_points`)."""
    from gnibench.suite.runs import sampling

    rec = problem.record
    options = tuple(keys["options"])
    initial = {f"{s}0" for s in rec.state}
    for o in options:
        if o not in initial:
            raise UserError(f"{where}.options: {o!r} is not an initial value of {problem.id}; "
                            f"allowed: {', '.join(sorted(initial))}")
    d, sample = len(options), keys["sample"]
    for name in ("low", "high", "center"):
        if keys.get(name) is not None and len(keys[name]) != d:
            raise UserError(f"{where}.{name}: bad {name} = {list(keys[name])}; allowed: {d} "
                            f"numbers, one per option")
    if sample in ("box", "shell") and any(a >= b for a, b in zip(keys["low"], keys["high"])):
        raise UserError(f"{where}: bad box low = {list(keys['low'])}, high = "
                        f"{list(keys['high'])}; allowed: low < high in every coordinate")
    if sample in ("circle",) and d != 2:
        raise UserError(f"{where}: a circle needs two options (got {d})")
    curve = None
    seed = keys.get("seed") or 0
    if sample == "box":
        points = sampling.box(keys["low"], keys["high"], keys["n"], seed)
    elif sample == "shell":
        points = sampling.shell(problem, list(options), keys["low"], keys["high"],
                                dict(keys["level"]), keys["n"], seed, where)
    elif sample == "list":
        points = _listed(keys["points"], d, f"{where}.points")
        seed = None
    elif sample == "circle":
        points = sampling.circle(keys["center"], keys["radius"], keys["n"])
        curve, seed = ("circle", tuple(keys["center"]), float(keys["radius"])), None
    else:
        vertices = _listed(keys["vertices"], d, f"{where}.vertices")
        if len(vertices) < 3:
            raise UserError(f"{where}.vertices: needs at least 3 vertices")
        if np.any(np.linalg.norm(np.diff(np.vstack([vertices, vertices[:1]]), axis=0),
                                 axis=1) == 0):
            raise UserError(f"{where}.vertices: two consecutive vertices are equal")
        points = sampling.polygon(vertices, keys["n"])
        curve, seed = ("polygon", tuple(map(tuple, vertices.tolist()))), None
    n = len(points)
    keep = keys.get("keep")
    if keep == "all":
        kept = tuple(range(n))
    elif keep is None:
        kept = ()
    elif isinstance(keep, int):
        kept = tuple(range(min(keep, n)))
    else:
        bad = [k for k in keep if k >= n]
        if bad:
            raise UserError(f"{where}.keep: orbit {bad[0]} does not exist; allowed: indices from "
                            f"0 to {n - 1}")
        kept = tuple(sorted(set(keep)))
    for values in points:
        rec.validate({**problem.values, **dict(zip(options, map(float, values)))})
    return EnsembleSpec(options, sample, np.ascontiguousarray(points, dtype=np.float64), kept,
                        keys.get("chunk") or CHUNK, 0, n, curve, seed)


def _listed(value, dim: int, where: str) -> np.ndarray:
    for k, point in enumerate(value):
        if len(point) != dim:
            raise UserError(f"{where}[{k}]: bad point {list(point)!r}; allowed: a list of {dim} "
                            f"numbers (one per option)")
    return np.array(value, dtype=float)
