"""rebound (IAS15, WHFast) for gravitational N-body problems: adapters and the integration loop.

An :class:`NBodyAdapter` says how a problem's state maps to rebound particles and back; a problem
without one is refused with a UserError. Used by :mod:`gnibench.suite.cell.reference` (IAS15 references) and
:mod:`gnibench.methods.external` (``rebound-ias15``, ``rebound-whfast``).
"""
from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from gnibench.methods.engines.base import EngineRun
from gnibench.suite.foundation.errors import UserError


@dataclass(frozen=True)
class Body:
    """Names of a body's position and momentum components in the problem state (None: zero)."""

    q: tuple[str | None, str | None, str | None]
    p: tuple[str | None, str | None, str | None]


@dataclass(frozen=True)
class NBodyAdapter:
    """How a problem's state maps to rebound particles and back.

    Two layouts. ``central``: the state is the motion of test particles relative to a fixed central
    body of gravitational parameter mu, with unit mass, so p = v (Kepler, [HLW] (2.2), [B] (5.1)).
    Rebound gets G = 1, a central mass mu and massless particles. ``nbody``: every body is in the
    state, p_i = m_i v_i ([HLW] (2.12)), with G and the masses taken from the problem.
    """

    bodies: tuple[Body, ...]
    mu: Callable | None = None                    # central: problem_bound -> mu
    G: Callable | None = None                     # nbody: problem_bound -> G
    masses: Callable | None = None                # nbody: problem_bound -> masses

    def particles(self, problem_bound, y) -> tuple[float, list[dict]]:
        """(G, [particle dicts]) for rebound's ``Simulation.add``."""
        at = dict(zip(problem_bound.record.state, (float(v) for v in y)))

        def vec(names, scale=1.0):
            return [at[n] / scale if n is not None else 0.0 for n in names]

        if self.mu is not None:
            out = [{"m": float(self.mu(problem_bound))}]
            for b in self.bodies:
                (x, yy, z), (vx, vy, vz) = vec(b.q), vec(b.p)
                out.append({"m": 0.0, "x": x, "y": yy, "z": z, "vx": vx, "vy": vy, "vz": vz})
            return 1.0, out
        masses = self.masses(problem_bound)
        out = []
        for b, m in zip(self.bodies, masses):
            (x, yy, z), (vx, vy, vz) = vec(b.q), vec(b.p, m)
            out.append({"m": float(m), "x": x, "y": yy, "z": z, "vx": vx, "vy": vy, "vz": vz})
        return float(self.G(problem_bound)), out

    def state(self, problem_bound, xyz: np.ndarray, vxyz: np.ndarray) -> np.ndarray:
        """The problem state from particle positions and velocities (arrays (N, 3))."""
        index = {n: k for k, n in enumerate(problem_bound.record.state)}
        y = np.zeros(len(index))
        if self.mu is not None:
            rel_x, rel_v, scale = xyz[1:] - xyz[0], vxyz[1:] - vxyz[0], [1.0] * len(self.bodies)
        else:
            rel_x, rel_v, scale = xyz, vxyz, self.masses(problem_bound)
        for b, x, v, m in zip(self.bodies, rel_x, rel_v, scale):
            for k in range(3):
                if b.q[k] is not None:
                    y[index[b.q[k]]] = x[k]
                if b.p[k] is not None:
                    y[index[b.p[k]]] = m * v[k]
        return y


def kepler_mu(problem_bound) -> float:
    """mu of a Kepler problem, read off its own vector field: p1' = -mu at q = e1, p = 0."""
    import sympy as sp
    from gnibench.problems.codegen import symbolic

    rec = problem_bound.record
    ys, ps, rhs, _ = symbolic(rec)
    body = ADAPTERS[rec.id].bodies[0]
    point = {c: float(v) for c, v in zip(ps, rec.par(problem_bound.values))}

    def accel(r: float) -> float:
        at = {y: (r if name == body.q[0] else 0.0) for y, name in zip(ys, rec.state)}
        return float(sp.sympify(rhs[rec.state.index(body.p[0])]).subs({**point, **at}))

    mu = -accel(1.0)
    if not (mu > 0 and math.isclose(-accel(2.0), mu / 4, rel_tol=1e-12)):
        raise ValueError(f"{rec.id}: the vector field is not a Kepler field -mu q/|q|^3")
    return mu


_KEPLER_2D = NBodyAdapter(bodies=(Body(q=("q1", "q2", None), p=("p1", "p2", None)),), mu=kepler_mu)
_KEPLER_3D = NBodyAdapter(bodies=(Body(q=("q1", "q2", "q3"), p=("p1", "p2", "p3")),), mu=kepler_mu)

# [HLW] (2.12): bodies 0 (sun) .. 5 (Pluto), state p0x..p5z, q0x..q5z (problems/outer_solar_system.py)
_OUTER_SOLAR_SYSTEM = NBodyAdapter(
    bodies=tuple(Body(q=(f"q{i}x", f"q{i}y", f"q{i}z"), p=(f"p{i}x", f"p{i}y", f"p{i}z"))
                 for i in range(6)),
    G=lambda pb: pb.values["G"],
    masses=lambda pb: tuple(pb.values[f"m{i}"] for i in range(6)),
)

ADAPTERS: dict[str, NBodyAdapter] = {
    "kepler-2d": _KEPLER_2D,
    "kepler-3d": _KEPLER_3D,
    "outer-solar-system": _OUTER_SOLAR_SYSTEM,
}


def adapter(problem) -> NBodyAdapter:
    """The rebound adapter of a problem record, or a UserError naming the problems that have one."""
    if problem.id not in ADAPTERS:
        from gnibench.problems import REGISTRY

        have = ", ".join(k for k in ADAPTERS if k in REGISTRY)
        raise UserError(f"rebound integrates only gravitational N-body problems; problem "
                        f"{problem.id} has no rebound adapter (have one: {have})")
    return ADAPTERS[problem.id]


def rebound_propagate(problem_bound, t: np.ndarray, integrator: str = "ias15",
                      epsilon: float = 1e-9, h: float | None = None,
                      step_counts: np.ndarray | None = None, h_last: float | None = None
                      ) -> EngineRun:
    """Integrate an N-body problem with rebound onto the sample times ``t``.

    IAS15 (adaptive, ``epsilon``) lands exactly on every sample (``exact_finish_time=1``). WHFast
    takes fixed steps ``h``: ``step_counts[k]`` steps up to sample k, the very last one of length
    ``h_last`` (as the compiled fixed-step driver does), so both sample the same times.
    """
    import rebound

    rec = problem_bound.record
    ad = adapter(rec)
    t0 = time.perf_counter()
    G, parts = ad.particles(problem_bound, rec.y0(problem_bound.values))
    sim = rebound.Simulation()
    sim.G = G
    sim.integrator = integrator
    if integrator == "ias15":
        sim.integrator.epsilon = float(epsilon)
    else:
        sim.dt = float(h)
    for p in parts:
        sim.add(**p)
    if ad.mu is not None:
        sim.N_active = 1                       # the bodies of the state are test particles
    n = sim.N
    xyz, vxyz = np.empty(3 * n), np.empty(3 * n)
    rows = len(t)
    y = np.empty((rows, rec.dim))
    steps = np.zeros(rows, dtype=np.int64)
    setup = time.perf_counter() - t0
    status, reason, done = "ok", "", 0
    t1 = time.perf_counter()
    for k in range(rows):
        try:
            if integrator == "ias15":
                sim.integrate(float(t[k]), exact_finish_time=1)
            else:
                todo = int(step_counts[k]) - int(sim.steps_done)
                last = k == rows - 1 and h_last is not None and h_last != h
                if todo > (1 if last else 0):
                    sim.steps(todo - (1 if last else 0))
                if last and todo > 0:
                    sim.dt = float(h_last)
                    sim.steps(1)
        except Exception as e:  # noqa: BLE001 - rebound's errors are integration failures
            status, reason = "nonfinite", f"rebound stopped: {type(e).__name__}: {e}"
            break
        sim.serialize_particle_data(xyz=xyz, vxvyvz=vxyz)
        y[k] = ad.state(problem_bound, xyz.reshape(n, 3), vxyz.reshape(n, 3))
        steps[k] = sim.steps_done
        if not np.all(np.isfinite(y[k])):
            status, reason = "nonfinite", f"state became non-finite near t = {float(t[k]):.17g}"
            break
        done = k + 1
    seconds = time.perf_counter() - t1
    y, steps = y[:done], steps[:done]
    if integrator == "whfast":
        # The DEFAULT kernel evaluates the interaction forces once per step ([Rein & Tamayo 2015]).
        nfev, nfev_doc = steps.astype(float), "interaction-force evaluations (one per step)"
    else:
        nfev, nfev_doc = np.full(done, np.nan), "not exposed (IAS15 predictor-corrector iterations)"
    info = {"engine": f"rebound {rebound.__version__}", "integrator": integrator,
            "steps": "rebound steps_done", "nfev": nfev_doc}
    if integrator == "ias15":
        info["epsilon"] = float(epsilon)
    return EngineRun(y=y, y_full=None, steps=steps, nfev=nfev, status=status, reason=reason,
                     setup_seconds=setup, seconds=seconds, info=info)
