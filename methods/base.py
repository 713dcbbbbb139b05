"""The method and modifier records: self-describing, with a parameter schema.

``gnibench list methods``, the spec parser, the structure checks and the registry-wide tests are all
driven by these records. Each compiled method also carries ``generate(ctx) -> str``, its family's
step writer (methods/assembly/steps): the text of its ``make_ws()`` and ``step(y, h, par, ws) ->
(y1, nfev, njev, status)`` for one cell (see :mod:`gnibench.methods.assembly`).
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from gnibench.methods.summation import sum_param
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.foundation.params import Param
from gnibench.suite.foundation.registries import Registered

H_PARAM = Param("h", 0.01, "step size (default: 0.01 time scales of the problem)", low=0.0,
                low_open=True, scaled=True)
NEWTON_PARAMS = (
    Param("newton_maxit", 50, "maximum Newton iterations per step", kind="int", low=1, high=1000,
          show_default=False),
)


def adaptive_params(tol: float) -> tuple[Param, ...]:
    """Options of every adaptive method (Hairer's codes): tolerances, initial and maximal step,
    step budget; relevant only when ``adaptive`` is true."""
    only = ("adaptive", True)
    return (
        Param("rtol", tol, "relative tolerance", low=0.0, low_open=True, only_if=only),
        Param("atol", tol, "absolute tolerance", low=0.0, low_open=True, only_if=only),
        Param("h0", 0.0, "initial step (0: Hairer's HINIT heuristic)", low=0.0, only_if=only,
              show_default=False),
        Param("hmax", 0.0, "maximal step (0: the whole interval)", low=0.0, only_if=only,
              show_default=False),
        Param("max_steps", 100000, "maximal number of steps (Hairer's NMAX)", kind="int", low=1,
              only_if=only, show_default=False),
    )


#: how a method runs (``Method.kind``): a compiled gnibench kernel, an external engine
#: (heyoka, rebound: ``ExternalMethod.run``), or Python code of the user's (user definitions)
KINDS = ("compiled", "external", "python")


@dataclass(frozen=True)
class Method(Registered):
    """A base integrator.

    ``needs`` lists the problem structure the method requires: ``partition`` (two blocks u, v as in
    [HLW] (1.8)). ``symplectic`` means symplectic for Hamiltonian problems in canonical partition.
    ``field_modifiers_refused``, when set, says why the method cannot integrate a field changed by a
    modifier (observer, penalty); the spec parser then refuses such a modifier at validation.
    ``kind`` says how it runs (:data:`KINDS`); ``origin``, where a user definition comes from
    (None for the shipped methods; :mod:`gnibench.suite.foundation.registries`), and
    ``definition`` its text.
    ``summation``, when set, offers the option ``sum`` (methods/summation.py) with that default:
    ``plain`` for the seeds' methods, ``compensated`` for high-accuracy families whose round-off
    would otherwise dominate their truncation error. ``runtime`` names the options passed to the
    compiled step at run time (in ``par``) rather than written into its module.
    """

    registry = "method"

    id: str
    family: str
    order: int
    reference: str
    doc: str
    generate: Callable[[Any], str]
    params: tuple[Param, ...] = (H_PARAM,)
    implicit: bool = False
    symplectic: bool = False
    symmetric: bool = False
    needs: tuple[str, ...] = ()
    explicit_when: str = ""          # e.g. "separable": explicit for problems with that structure
    field_modifiers_refused: str = ""  # why the method cannot take +observer/+penalty ("" if it can)
    data: Any = None
    aliases: tuple[str, ...] = field(default=())
    kind: str = "compiled"
    origin: Any = None
    definition: str = ""             # a user definition's text (part of a stored cell's key)
    summation: str | None = None     # default of the option sum (plain|compensated); None: none
    #: options the compiled step reads from ``par`` (after the problem's and the modifiers'
    #: values; ``Context.extra["par_at"]`` gives where) instead of from its module's text: cells
    #: that differ only in them share one kernel (the iteration counts of a sweep)
    runtime: tuple[str, ...] = ()
    #: numbers the compiled step reads from ``par`` after the runtime options
    #: (``Context.extra["data_at"]`` gives where) instead of from its module's text: the methods
    #: of a family that differ only in them share one kernel per problem (the compositions'
    #: coefficients, methods/compositions.py)
    runtime_data: tuple[float, ...] = ()

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValueError(f"method {self.id}: bad kind {self.kind!r}; allowed: {KINDS}")
        if self.summation is not None and all(p.name != "sum" for p in self.params):
            object.__setattr__(self, "params", self.params + (sum_param(self.summation),))

    def check_structure(self, problem, has_modifiers: bool) -> None:
        """Refuse, with a clear error, a problem that lacks the structure this method needs."""
        if "partition" in self.needs and problem.partition is None:
            raise UserError(
                f"method {self.id} needs a partitioned system (blocks u, v; [HLW] (1.8)), "
                f"but problem {problem.id} declares no partition; use a method that does not need one")

    def describe(self) -> dict:
        return {
            "id": self.id, "family": self.family, "kind": self.kind, "order": self.order,
            "reference": self.reference, "doc": self.doc,
            "properties": {"implicit": self.implicit,
                           "explicit": (f"when {self.explicit_when}" if self.explicit_when
                                        else not self.implicit),
                           "symplectic": self.symplectic, "symmetric": self.symmetric,
                           "needs_partition": "partition" in self.needs},
            "params": [p.describe() for p in self.params],
        }


@dataclass(frozen=True)
class Modifier(Registered):
    """A vector-field modifier (observer, penalty): adds a term to F that any method then integrates.

    ``resolve(values, problem)`` fills in defaults that depend on the problem (the observed integrals)
    and checks them; ``generate(ctx, index, offset)`` returns the source of ``<name>_term(y, par)`` and
    ``<name>_jac(y, par, J)``; ``runtime(values, h0)`` the numbers it reads from ``par``.
    """

    registry = "modifier"

    id: str
    reference: str
    doc: str
    params: tuple[Param, ...]
    resolve: Callable
    generate: Callable
    runtime: Callable
    runtime_size: Callable
    needs_independent: bool = False    # [B] §2: rank D_H = q on Γ, else D_H D_Hᵀ is singular
    kind: str = "field"                # "field": adds a term to F; "step": maps each step's result

    def describe(self) -> dict:
        return {"id": self.id, "reference": self.reference, "doc": self.doc, "kind": "modifier",
                "acts_on": self.kind,
                "params": [p.describe() for p in self.params]}
