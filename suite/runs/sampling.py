"""Initial sets of an ensemble: N initial conditions of one problem, drawn once, reproducibly.

The sampled coordinates are initial-value options of the problem (``q0``, ``p20``: the option
``<state>0`` sets the state component ``<state>``); the others keep the problem's initial point
(its catalog value, or the option given in the problem spec). Five shapes:

* ``box``: N points uniform in the box ``low <= x <= high`` (one bound per option), drawn by
  numpy's ``Generator(PCG64(seed))``: ``x = low + (high - low) * rng.random((N, d))``, row by
  row. The same seed gives the same points bit for bit on every machine numpy runs on (PCG64 and
  ``Generator.random`` are numpy's stable stream; the affine map is one multiplication and one
  addition per value).
* ``shell``: points of a level set of first integrals, ``{I_k(y) = c_k}`` (``level = {H = c}``,
  one or more integrals), inside the box. Candidates are drawn from the box as above; each is
  moved onto the level set by Newton's method along the gradients (the minimum-norm
  Gauss–Newton step in the sampled coordinates, :func:`project`); a candidate whose iteration
  does not converge (a zero gradient, a level set the candidate's line never meets) or ends
  outside the box (another component of the level set: an escaping orbit of Hénon–Heiles) is
  dropped and the next candidate is taken, in the order drawn, until N are placed. The
  projection runs in plain Python on the problem's generated functions (IEEE double, one value
  at a time), so the points are the same bits whatever the number of workers: they are made
  once, where the experiment is read.
* ``list``: the points given.
* ``circle``, ``polygon``: N points on a closed curve, in order (counterclockwise from angle 0;
  evenly spaced by arc length from the first vertex): a set's boundary, carried by the flow
  ([HLW] Figs 1.1 and 1.3; :mod:`gnibench.suite.metrics.area`).

The distribution on a shell is the box's pushed along the gradients, not the surface measure of
the level set; it covers the part of the level set inside the box that the box's points project
to.
"""
from __future__ import annotations

import math

import numpy as np
from gnibench.suite.foundation.errors import UserError

SHAPES = ("box", "shell", "list", "circle", "polygon")
NEWTON_ITERATIONS = 50
#: |I_k(y) - c_k| <= TOLERANCE * max(1, |c_k|) for a point on the level set
TOLERANCE = 8 * 2.220446049250313e-16
MAX_DRAWS = 100          # candidates drawn for a shell: at most this many times N


def box(low, high, n: int, seed: int) -> np.ndarray:
    """n points uniform in the box (see the module docstring), shape (n, d)."""
    low, high = np.asarray(low, dtype=float), np.asarray(high, dtype=float)
    rng = np.random.Generator(np.random.PCG64(seed))
    return low + (high - low) * rng.random((n, len(low)))


def project(x: np.ndarray, y0: list[float], at: list[int], functions: list, gradients: list,
            levels: list[float], par) -> np.ndarray | None:
    """The point of the level set {I_k = c_k} reached from ``x`` (the sampled coordinates, placed
    at the state indices ``at`` of ``y0``) by Newton's method: x <- x - J^T (J J^T)^-1 (I(y) - c),
    J the gradients of the integrals in the sampled coordinates (the minimum-norm step onto the
    linearized level set); None when it does not converge in :data:`NEWTON_ITERATIONS`
    iterations or J J^T is singular."""
    y = list(y0)
    x = [float(v) for v in x]
    for _ in range(NEWTON_ITERATIONS):
        for i, v in zip(at, x):
            y[i] = v
        state = tuple(y)
        r = [f(state, par) - c for f, c in zip(functions, levels)]
        if not all(math.isfinite(v) for v in r):
            return None
        if all(abs(v) <= TOLERANCE * max(1.0, abs(c)) for v, c in zip(r, levels)):
            return np.array(x)
        J = [[g(state, par)[i] for i in at] for g in gradients]
        if len(J) == 1:                        # one integral: x -= g r / |g|^2, in floats
            g = J[0]
            norm = math.fsum(v * v for v in g)
            if not (math.isfinite(norm) and norm > 0):
                return None
            x = [a - v * r[0] / norm for a, v in zip(x, g)]
            continue
        J = np.array(J, dtype=float)
        if not np.all(np.isfinite(J)):
            return None
        try:
            step = J.T @ np.linalg.solve(J @ J.T, np.array(r))
        except np.linalg.LinAlgError:
            return None
        x = [a - b for a, b in zip(x, step.tolist())]
    return None


def shell(problem, options: list[str], low, high, levels: dict[str, float], n: int, seed: int,
          where: str) -> np.ndarray:
    """n points of the level set ``levels`` (see the module docstring), shape (n, d)."""
    from gnibench.problems.codegen import problem_meta, python_functions

    rec = problem.record
    names = list(problem_meta(rec)["integrals"])
    for name in levels:
        if name not in names:
            raise UserError(f"{where}.level: {problem.id} has no integral {name!r}; allowed: "
                            f"{', '.join(names) or 'none'}")
    fns = python_functions(rec)
    ks = [names.index(name) for name in levels]
    functions = [fns[f"integral_{k}"] for k in ks]
    gradients = [fns[f"grad_{k}"] for k in ks]
    at = [rec.state.index(o[:-1]) for o in options]
    y0 = list(rec.y0(problem.values))
    par = tuple(rec.par(problem.values))
    targets = [float(v) for v in levels.values()]
    rng = np.random.Generator(np.random.PCG64(seed))
    low, high = np.asarray(low, dtype=float), np.asarray(high, dtype=float)
    out: list[np.ndarray] = []
    drawn = 0
    while len(out) < n:
        if drawn >= MAX_DRAWS * n:
            raise UserError(f"{where}: only {len(out)} of {n} points reached the level set "
                            f"{levels} from {drawn} points of the box; allowed: a box whose "
                            f"points the level set's gradients lead onto it")
        batch = low + (high - low) * rng.random((n, len(low)))
        drawn += n
        for x in batch:
            p = project(x, y0, at, functions, gradients, targets, par)
            if p is not None and np.all((low <= p) & (p <= high)):
                out.append(p)
                if len(out) == n:
                    break
    return np.array(out)


def circle(center, radius: float, n: int) -> np.ndarray:
    """n points on the circle, counterclockwise from angle 0."""
    angle = 2 * np.pi * np.arange(n) / n
    return np.array(center, dtype=float) + radius * np.column_stack([np.cos(angle),
                                                                     np.sin(angle)])


def circle_at(center, radius: float, s: np.ndarray) -> np.ndarray:
    """The circle's points at curve parameters s in [0, 1) (s = k/n: :func:`circle`'s)."""
    angle = 2 * np.pi * np.asarray(s, dtype=float)
    return np.array(center, dtype=float) + radius * np.column_stack([np.cos(angle),
                                                                     np.sin(angle)])


def polygon(vertices, n: int) -> np.ndarray:
    """n points evenly spaced by arc length along the closed polygon, from its first vertex."""
    closed, arc = _outline(vertices)
    return _along(closed, arc, arc[-1] * np.arange(n) / n)


def polygon_at(vertices, s: np.ndarray) -> np.ndarray:
    """The closed polygon's points at arc-length fractions s in [0, 1)."""
    closed, arc = _outline(vertices)
    return _along(closed, arc, arc[-1] * np.asarray(s, dtype=float))


def _outline(vertices) -> tuple[np.ndarray, np.ndarray]:
    vertices = np.asarray(vertices, dtype=float)
    closed = np.vstack([vertices, vertices[:1]])
    edges = np.linalg.norm(np.diff(closed, axis=0), axis=1)
    return closed, np.concatenate([[0.0], np.cumsum(edges)])


def _along(closed: np.ndarray, arc: np.ndarray, at: np.ndarray) -> np.ndarray:
    return np.column_stack([np.interp(at, arc, closed[:, j]) for j in range(closed.shape[1])])
