"""The problem record: one definition per problem, from which everything else is derived.

A problem module defines a :class:`Problem` whose ``model`` builds sympy expressions: either a
Hamiltonian in canonical variables ([HLW] (1.10): p' = -H_q, q' = H_p) or an explicit right-hand
side, plus its named first integrals. From that single source :mod:`gnibench.problems.codegen` derives the
compiled vector field, its Jacobian, the integrals and their gradients D_H, and the partition
structure. Exact solutions, where known, are plain numpy functions of the same record.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from gnibench.suite.foundation.errors import UserError
from gnibench.suite.foundation.params import Bound, Param
from gnibench.suite.foundation.registries import Registered


@dataclass(frozen=True)
class Model:
    """What ``Problem.model`` returns: a Hamiltonian or a right-hand side, and the integrals."""

    integrals: dict[str, Any]
    hamiltonian: Any = None
    rhs: tuple | None = None
    # q-partial first integrals [B] (2.12): name -> (h_k, row k of L); the row is one expression
    # (diagonal entry L_kk) or a dict {partial name: L_kj}. D_H F = L H; Gamma_0 = {H = 0}.
    partial_integrals: dict[str, tuple] = field(default_factory=dict)


@dataclass(frozen=True)
class Section:
    """A Poincaré section, part of a problem's definition.

    The section is {g(y) = 0} crossed in the direction where ``condition(y) > 0`` holds
    (e.g. G-S: g = p1, condition p2 > 0). ``g`` and ``condition`` map the sympy namespace ``S`` to
    expressions. ``coords`` names the state components (or ``chart_coords``) recorded at a crossing;
    ``chart``, if given, is ``chart(y) -> int`` (numpy, 1-based) for multi-chart sections such as
    so(4)'s Γ1..Γ8, and ``charts`` is their number (8 there).
    """

    name: str
    g: Callable[[Any], Any]
    condition: Callable[[Any], Any]
    coords: tuple[str, ...]
    reference: str = ""
    chart: Callable | None = None
    charts: int = 0


@dataclass(frozen=True)
class Boundary:
    """The boundary of a fundamental domain, for engines that locate its crossings exactly.

    The compiled methods apply ``Problem.post_step`` after a step that has left the domain; an
    event-locating engine (heyoka) stops at the crossing itself and applies the identification of
    the side crossed. ``sides(S)`` gives one sympy expression g_k per side, with the domain
    {g_k > 0 for all k}; ``maps(S)`` gives, per side, the state (tuple of sympy expressions) to
    which a point of side k is identified, the same map as ``post_step`` on that side.
    """

    sides: Callable[[Any], tuple]
    maps: Callable[[Any], tuple]
    reference: str = ""


@dataclass(frozen=True)
class Transform:
    """A problem transform (e.g. K-S regularization): switched on by the boolean option ``option``.

    ``to_transformed(y0, values) -> (values of ``problem``)`` gives the transformed problem's
    option values (parameters and initial point); ``back(Z, values) -> (t, Y)`` maps its samples
    to the original time and state, so every metric of the original problem applies unchanged.
    ``time`` names the transformed system's state component that is the original time (K-S: t,
    with the fictitious time s as independent variable): a time grid (``dt_out``) is laid in it.
    """

    option: str
    problem: Any
    to_transformed: Callable
    back: Callable
    doc: str = ""
    time: str | None = None


@dataclass(frozen=True)
class Problem(Registered):
    """A self-describing problem record.

    Parameters
    ----------
    id, title, reference:
        Public id, one-line title and place in the seeds.
    state:
        Names of the state components, in order.
    params:
        Model parameters (numbers passed to the compiled code at run time, in this order).
    model:
        ``model(S)`` with ``S.<name>`` the sympy symbol of every state component and parameter;
        returns a :class:`Model`.
    initial:
        ``initial(values) -> tuple`` default initial point from the parameter values.
    canonical:
        ``(p names, q names)`` when ``model`` gives a Hamiltonian.
    partition:
        ``(u names, v names)`` for partitioned methods ([HLW] (1.8)); defaults to ``canonical``.
    exact:
        ``exact(t, y0, values) -> array (len(t), N)``, the exact solution, or None.
    period:
        ``period(values) -> float``, the period of the solution from the option values (initial
        point included), or None when the problem has none. Metrics sampled at whole periods
        (η(nT), [B] §5.2) need it.
    notes:
        Choices made where the seeds are silent (also shown by ``gnibench list``).
    sections:
        Poincaré sections (:class:`Section`) that belong to the problem.
    time_scale:
        ``time_scale(values) -> float``, the problem's characteristic time (default: 1); default
        step sizes and output intervals are 0.01 of it.
    post_step:
        Identification map applied after every accepted step, e.g. the homography that maps a
        geodesic back into the fundamental octagon ([B] (8.3)-(8.4)). A numba-compilable template
        function ``post_step(y, par) -> y`` (its free names bound in the kernel module: methods/assembly/bindings.py).
    origin, definition:
        Where a user definition comes from (None for the shipped problems): a picklable object
        whose ``load()`` defines it in a process that lacks it
        (:mod:`gnibench.suite.foundation.registries`); and the definition's text, part of the key
        of the generated code and of a stored cell ("" for the shipped problems, whose source
        files are hashed instead).
    """

    registry = "problem"

    id: str
    title: str
    reference: str
    state: tuple[str, ...]
    params: tuple[Param, ...]
    model: Callable[[Any], Model]
    initial: Callable[[dict], tuple]
    canonical: tuple[tuple[str, ...], tuple[str, ...]] | None = None
    partition: tuple[tuple[str, ...], tuple[str, ...]] | None = None
    exact: Callable | None = None
    period: Callable[[dict], float] | None = None
    notes: str = ""
    sections: tuple[Section, ...] = ()
    post_step: Callable | None = None
    boundary: Boundary | None = None
    transform: Transform | None = None
    time_scale: Callable[[dict], float] | None = None
    model_params: tuple[str, ...] = field(default=())
    origin: Any = None
    definition: str = ""

    def __post_init__(self):
        if self.partition is None and self.canonical is not None:
            object.__setattr__(self, "partition", self.canonical)
        if self.partition is not None:
            u, v = self.partition
            if sorted(u + v) != sorted(self.state):
                raise ValueError(f"{self.id}: partition {self.partition} does not cover {self.state}")
        # Model parameters are the declared ones; initial-value options are appended as <name>0.
        # Idempotent, so dataclasses.replace (which passes the extended params back in) works.
        init_names = {f"{s}0" for s in self.state}
        declared = tuple(p for p in self.params if p.name not in init_names)
        object.__setattr__(self, "model_params", tuple(p.name for p in declared))
        inits = tuple(Param(f"{s}0", None, f"initial value of {s} (default: catalog value)")
                      for s in self.state)
        object.__setattr__(self, "params", declared + inits)

    @property
    def dim(self) -> int:
        return len(self.state)

    def validate(self, values: dict) -> None:
        """Hook for cross-parameter checks; raise UserError. Default: none."""

    def transformed(self, values: dict):
        """The Bound of the transformed problem when this problem's transform is switched on."""
        if self.transform is None or not values.get(self.transform.option):
            return None

        rec = self.transform.problem
        tvalues = {p.name: p.default for p in rec.params}
        tvalues.update(self.transform.to_transformed(self.y0(values), values))
        return Bound(rec, tvalues)

    def time_scale_of(self, values: dict) -> float:
        """The problem's characteristic time (``time_scale``, default 1: the catalog's units make
        the motion of order one per unit time). Default step sizes and output intervals are 0.01
        of it, so a problem in days (the outer solar system) does not get 0.01-day defaults."""
        if self.time_scale is not None:
            return float(self.time_scale(values))
        if self.period is not None:                   # 1/frequency: 1 for the catalog orbits
            return float(f"{self.period(values) / (2 * math.pi):.2g}")
        return 1.0

    def par(self, values: dict) -> tuple[float, ...]:
        """The run-time parameter tuple for the compiled code (model parameters, in order)."""
        return tuple(float(values[n]) for n in self.model_params)

    def y0(self, values: dict) -> tuple[float, ...]:
        """Initial point: the catalog default, with any ``<name>0`` option overriding it."""
        base = tuple(float(x) for x in self.initial(values))
        out = tuple(values.get(f"{s}0") if values.get(f"{s}0") is not None else b
                    for s, b in zip(self.state, base))
        return out

    def describe(self) -> dict:
        from gnibench.problems.codegen import problem_meta

        meta = problem_meta(self)
        return {
            "id": self.id, "title": self.title, "reference": self.reference,
            "state": list(self.state), "integrals": meta["integrals"],
            "partition": [list(b) for b in self.partition] if self.partition else None,
            "separable": meta["explicit_u"] and meta["explicit_v"] if self.partition else False,
            "exact_solution": self.exact is not None, "period": self.period is not None,
            "params": [p.describe() for p in self.params], "notes": self.notes,
        }


def require(cond: bool, message: str) -> None:
    """Raise a UserError unless cond holds (for Problem.validate hooks)."""
    if not cond:
        raise UserError(message)
