"""The external engines, heyoka and rebound, driven from a problem's single definition.

Both serve twice: as reference solutions (:mod:`gnibench.suite.cell.reference`) and as competitor methods
(:mod:`gnibench.methods.external`).

* **heyoka** (Taylor's method, Biscani & Izzo 2021). The system is built from the problem's sympy
  model (:func:`gnibench.problems.codegen.symbolic`) with ``heyoka.from_sympy``. Model parameters become
  runtime parameters ``heyoka.par[i]``, so one JIT-compiled integrator serves every parameter value.
  Constants that are not exactly representable as doubles (sqrt(2), 1/3, ...) would be rounded
  to double by ``from_sympy``. They become runtime parameters as well, set in the working
  precision, so a real128 integration really integrates the model in real128. Numbers that are
  already doubles (the problem's parameters, initial values and grid times) are converted exactly.
* **rebound** (IAS15, WHFast): :mod:`gnibench.methods.engines.rebound`.

Both return an :class:`EngineRun` on a given sample grid.
"""
from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from gnibench.methods.engines.base import EngineRun
from gnibench.suite.foundation.errors import UserError

PRECISIONS = ("double", "long double", "real128")
_PRECISION_ALIASES = {"double": "double", "float64": "double", "long double": "long double",
                      "long-double": "long double", "longdouble": "long double",
                      "real128": "real128", "quad": "real128"}


def precision_name(text: str) -> str:
    """Canonical precision name ('double', 'long double', 'real128'), or a UserError."""
    name = _PRECISION_ALIASES.get(str(text).strip().lower())
    if name is None:
        raise UserError(f"bad precision {text!r}; allowed: {'|'.join(PRECISIONS)}")
    return name


def fp_type(precision: str):
    """The numpy / heyoka scalar type of a precision."""
    if precision == "double":
        return float
    if precision == "long double":
        return np.longdouble
    import heyoka

    if not hasattr(heyoka, "real128"):
        raise UserError("this heyoka build has no real128 (quadmath) support; use precision=long double")
    return heyoka.real128


def epsilon(precision: str) -> float:
    """Machine epsilon of a precision (the default Taylor tolerance)."""
    if precision == "double":
        return float(np.finfo(float).eps)
    if precision == "long double":
        return float(np.finfo(np.longdouble).eps)
    return 2.0 ** -112                                   # IEEE binary128: 113-bit significand


COMPACT_ABOVE = 8                              # heyoka compact mode for systems larger than this


# ---------------------------------------------------------------------------------------------
# heyoka


@dataclass(frozen=True)
class HeyokaSystem:
    """The heyoka form of a problem: equations, plus the constants heyoka must see as par[i]."""

    equations: list
    n_pars: int                                # heyoka counts par[i] up to the highest index used
    constants: tuple[str, ...]                 # decimal texts (40 digits) of par[n_model:]
    # (the boundary maps, evaluated by a cfunc, may use constants beyond the integrator's n_pars)
    variables: list = None                     # the heyoka state variables
    sides: list = None                         # Problem.boundary: g_k (domain: all g_k > 0) ...
    maps: list = None                          # ... and per side the identified state


_systems: dict[str, HeyokaSystem] = {}


def _exact_number(x) -> bool:
    """Does heyoka.from_sympy keep this constant exactly, in every precision?"""
    import sympy as sp

    if isinstance(x, sp.Integer) or x is sp.pi:
        return True
    if isinstance(x, sp.Float):
        return x._prec <= 53
    if isinstance(x, sp.Rational):
        return x.q & (x.q - 1) == 0                      # dyadic: a power-of-two denominator
    return False


def _lift_constants(expr, table: dict):
    """Replace each maximal constant subexpression that is not exact by a placeholder symbol."""
    import sympy as sp

    if not expr.free_symbols:
        if _exact_number(expr):
            return expr
        if expr not in table:
            table[expr] = sp.Symbol(f"hy_const_{len(table)}")
        return table[expr]
    if not expr.args:
        return expr
    return expr.func(*[_lift_constants(a, table) for a in expr.args])


def check_heyoka(problem) -> None:
    """Refuse problems whose trajectories heyoka cannot follow: an identification map
    (``post_step``) needs its domain's boundary (``Problem.boundary``) for heyoka to locate the
    crossings."""
    if getattr(problem, "post_step", None) is not None and getattr(problem, "boundary", None) is None:
        raise UserError(f"problem {problem.id} maps the state after every step (post_step, e.g. back "
                        f"into a fundamental domain) but defines no boundary (Problem.boundary) "
                        f"for heyoka to locate the crossings")


def heyoka_system(problem) -> HeyokaSystem:
    """The heyoka equations of a problem record, built once per process from its sympy model."""
    from gnibench.problems.codegen import _source_hash, symbolic

    key = f"{problem.id}-{_source_hash(problem)}"
    if key in _systems:
        return _systems[key]
    import heyoka as hy
    import sympy as sp

    ys, ps, rhs, _ = symbolic(problem)
    table: dict = {}
    lifted = [_lift_constants(sp.sympify(r), table) for r in rhs]
    sides, maps = [], []
    if problem.boundary is not None:
        from types import SimpleNamespace

        ns = SimpleNamespace(**dict(zip(problem.state, ys)), **dict(zip(problem.model_params, ps)))
        sides = [_lift_constants(sp.sympify(g), table) for g in problem.boundary.sides(ns)]
    n_integrator = len(table)                  # constants of the ODE and its events come first
    if problem.boundary is not None:
        maps = [[_lift_constants(sp.sympify(c), table) for c in m] for m in problem.boundary.maps(ns)]
        if len(maps) != len(sides) or any(len(m) != len(ys) for m in maps):
            raise ValueError(f"{problem.id}: boundary needs one map of {len(ys)} components per side")
    xs = hy.make_vars(*[str(y) for y in ys])
    xs = xs if isinstance(xs, list) else [xs]
    s_dict = {y: x for y, x in zip(ys, xs)}
    s_dict.update({c: hy.par[i] for i, c in enumerate(ps)})
    s_dict.update({sym: hy.par[len(ps) + k] for k, sym in enumerate(table.values())})
    equations = [(x, hy.from_sympy(r, s_dict)) for x, r in zip(xs, lifted)]
    constants = tuple(str(sp.N(c, 40)) for c in table)
    used = set().union(*[r.free_symbols for r in lifted + sides])
    n_pars = len(ps) + n_integrator if n_integrator else 1 + max(
        (i for i, c in enumerate(ps) if c in used), default=-1)
    system = HeyokaSystem(equations, n_pars, constants, xs,
                          [hy.from_sympy(g, s_dict) for g in sides],
                          [[hy.from_sympy(c, s_dict) for c in m] for m in maps])
    _systems[key] = system
    return system


def heyoka_propagate(problem_bound, t: np.ndarray, precision: str = "double",
                     tol: float | None = None) -> EngineRun:
    """Integrate a problem with heyoka's adaptive Taylor method onto the sample times ``t``.

    ``tol`` defaults to the epsilon of the precision. Samples come from heyoka's dense output
    (``propagate_grid``), which is accurate to ``tol`` like the steps themselves.

    A problem with an identification map (``post_step``) gives its domain's boundary
    (``Problem.boundary``): each side is a terminal event, located by heyoka to the working
    precision; at a crossing the side's map (compiled by ``heyoka.cfunc`` in the working
    precision, so a real128 reference is not limited to double there) sends the state to the
    identified point and the integration restarts from it (:func:`_propagate_identified`). The
    samples are then the states mapped into the domain, as the compiled methods give them.
    """
    import heyoka as hy

    precision = precision_name(precision)
    fp = fp_type(precision)
    tol = epsilon(precision) if tol is None else float(tol)
    rec = problem_bound.record
    t0 = time.perf_counter()
    system = heyoka_system(rec)
    all_pars = [fp(float(x)) for x in rec.par(problem_bound.values)] + [fp(c) for c in system.constants]
    pars = all_pars[:system.n_pars]
    state = [fp(float(x)) for x in rec.y0(problem_bound.values)]
    # A domain boundary (Problem.boundary): one terminal event per side, g_k crossing zero
    # downwards (leaving the domain {g_k > 0}); the identification is applied at the crossing.
    events = [hy.t_event(g, direction=hy.event_direction.negative, fp_type=fp)
              for g in system.sides]
    # high_accuracy: compensated summation of the Taylor series; keeps round-off from growing
    # over long references at little cost. compact_mode for larger systems: the JIT compilation of
    # the fully unrolled Taylor recursion grows fast with the system (outer-solar-system, 36
    # equations: 7-15 s unrolled, 0.2 s compact, for steps about 2x slower).
    ta = hy.taylor_adaptive(system.equations, state, fp_type=fp, tol=fp(tol), pars=pars,
                            high_accuracy=True, compact_mode=rec.dim > COMPACT_ABOVE,
                            **({"t_events": events} if events else {}))
    identify = _identification(system, fp, all_pars, precision) if events else None
    setup = time.perf_counter() - t0

    step_ends: list[float] = []

    def count(integrator) -> bool:
        step_ends.append(float(integrator.time))
        return True

    grid = np.array([fp(float(x)) for x in t]) if precision == "real128" else np.asarray(t, fp)
    t1 = time.perf_counter()
    crossings = 0
    if identify is None:
        outcome, *_, full = ta.propagate_grid(grid, callback=count)
    else:
        outcome, full, crossings = _propagate_identified(ta, grid, identify, len(events), count)
    seconds = time.perf_counter() - t1

    y = np.asarray(full.astype(np.float64))
    ok = str(outcome).endswith("time_limit")
    rows = len(y)
    if not ok:
        finite = np.all(np.isfinite(y), axis=1)
        rows = int(np.argmin(finite)) if not finite.all() else len(y)
        y, full = y[:rows], full[:rows]
    ends = np.asarray(step_ends)
    steps = np.minimum(np.searchsorted(ends, np.asarray(t[:rows]), side="left") + 1, len(ends))
    steps[np.asarray(t[:rows]) <= 0.0] = 0
    info = {"engine": f"heyoka {hy.__version__}", "precision": precision, "tol": tol,
            "taylor_order": int(ta.order), "outcome": str(outcome).split(".")[-1],
            **({"identifications": crossings,
                "identification_precision": precision} if identify is not None else {}),
            "nfev": "not exposed: a Taylor step computes order-p series by automatic "
                    "differentiation, not f-evaluations"}
    return EngineRun(y=y, y_full=None if precision == "double" else full,
                     steps=steps.astype(np.int64), nfev=np.full(rows, np.nan),
                     status="ok" if ok else "nonfinite",
                     reason="" if ok else f"heyoka stopped with outcome {info['outcome']} at "
                                          f"t = {float(ta.time):.17g}",
                     setup_seconds=setup, seconds=seconds, info=info)


_identifications: dict = {}


def _identification(system: HeyokaSystem, fp, pars: list, precision: str) -> Callable:
    """``identify(y, side) -> y``: the map of the side crossed, then (near a vertex, where the image
    may lie beyond another side) the maps of any side still clearly violated, all evaluated by
    one compiled ``heyoka.cfunc`` in the working precision."""
    import heyoka as hy

    key = (id(system), precision)
    if key not in _identifications:
        n, m = len(system.variables), len(system.sides)
        outputs = list(system.sides) + [c for mp in system.maps for c in mp]
        cf = hy.cfunc(outputs, system.variables, fp_type=fp)
        _identifications[key] = (cf, n, m)
    cf, n, m = _identifications[key]
    kw = {"pars": np.array(pars)} if pars else {}
    slack = 2.0 ** 10 * epsilon(precision)    # |g| of a point just put on a side: a few ulps

    def identify(y, side: int):
        y = np.array(y)
        for _ in range(16):                    # each map moves the point towards the centre
            y = np.array(cf(y, **kw)[m + n * side: m + n * (side + 1)])
            g = [float(v) for v in cf(y, **kw)[:m]]
            side = int(np.argmin(g))
            if not g[side] < -slack:
                break
        return y

    return identify


def _propagate_identified(ta, grid: np.ndarray, identify: Callable, n_events: int, count):
    """Propagate to ``grid[-1]``, stopping at each terminal (boundary) event to identify.

    Between events, ``propagate_until(..., c_output=True)`` gives the dense output of the segment;
    the grid points before the crossing time are read from it, a grid point at or after the crossing
    from a later segment (so the samples are always the mapped states, and any number of crossings
    between two grid points is handled). Returns (outcome, samples, number of identifications).
    """
    import heyoka as hy

    full = np.empty((len(grid), len(ta.state)), dtype=ta.state.dtype)
    times = np.array([float(x) for x in grid])          # the grid times are doubles
    nxt, crossings = 0, 0
    while times[nxt] <= float(ta.time):                 # grid points at the start time
        full[nxt] = ta.state
        nxt += 1
        if nxt == len(grid):
            return hy.taylor_outcome.time_limit, full, crossings
    while True:
        outcome, _, _, _, c_out, _ = ta.propagate_until(grid[-1], c_output=True, callback=count)
        value = int(outcome.value)
        event = -n_events <= value <= -1
        reached = outcome == hy.taylor_outcome.time_limit
        end = len(grid) if reached else int(np.searchsorted(times, float(ta.time), side="left"))
        if end > nxt and c_out is not None:
            inner = end - 1 if reached else end
            if inner > nxt:
                full[nxt:inner] = c_out(grid[nxt:inner])
            nxt = inner
        if reached:
            full[-1] = ta.state
            return outcome, full, crossings
        if not event:
            return outcome, full[:nxt], crossings
        ta.state[:] = identify(ta.state, -value - 1)
        ta.reset_cooldowns()
        crossings += 1
