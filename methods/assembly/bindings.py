"""The binding tables: which code binds each name a driver's templates leave free.

A template (:mod:`gnibench.methods.assembly.templates`) is a plain function whose free names are
bound in the kernel module it is copied into. Who binds them is written here, per driver kind
and output (:data:`DRIVERS`) and per method family (:data:`FAMILIES`); the assembly
(:func:`gnibench.methods.assembly.assemble`) puts exactly these parts together, and
tests/kernels/test_assembly.py checks that every name each template of a module uses is bound
there, for every family, driver kind and output.

Every module also binds, whatever the cell (:data:`COMMON`): the header's constants (the state
dimension ``N``, ``NEWTON_MAXIT``, ``COMPENSATED``, the slots and status codes of
templates/slots.py, the event constants), the problem's functions (problems/codegen.py), the tuple
helpers, the compensated-summation carries, the linear algebra, the field ``f``/``fjac`` and the
step modifiers' ``project`` (fields.py), ``post_step`` and ``record_row``.

**A new driver kind** (e.g. a batched driver that runs N initial conditions through one compiled
loop calling the single-orbit loop): its loop template in templates/, one :class:`DriverKind`
entry here with its outputs, and a Python driver object in suite/cell/drivers.py.
**A new family**: its step writer in steps/ (``make_ws``, ``step``, ``step_sum``; and the
:data:`ADAPTIVE_PART` names if it runs the adaptive loop), one :class:`Family` entry here, and its
methods' records in methods/ (``Method.generate`` = the writer).
"""
from __future__ import annotations

from dataclasses import dataclass

from gnibench.methods.assembly.templates import adaptive, fixed

#: the loops' flags, module constants of every kernel module (True for the output's own)
FLAGS = ("GRID", "GRIDDED", "SECTION", "DENSE_OUTPUT", "SECTION_DENSE", "WITH_STAGES")


@dataclass(frozen=True)
class Output:
    """One output of a driver kind: the name Python knows the driver by, the flags its loop reads
    as True, and the parts it adds to the module (methods/assembly/drivers.py)."""

    name: str
    flags: tuple[str, ...] = ()
    parts: tuple[str, ...] = ()


@dataclass(frozen=True)
class DriverKind:
    """A compiled loop (a template, copied under its own name as the module's ``@entry``) and its
    outputs."""

    loop: object
    outputs: dict


DRIVERS = {
    # templates/fixed.py: nsteps steps of size h, t_n = n h
    "fixed": DriverKind(fixed.integrate, {
        "samples": Output("integrate"),
        "grid": Output("integrate_grid", ("GRID",), ("fixed_partial_step", "grid")),
        "section": Output("integrate_section", ("SECTION",), ("section",)),
    }),
    # templates/adaptive.py: adaptive steps to t_end, the family's attempt and controller
    "adaptive": DriverKind(adaptive.integrate_adaptive, {
        "samples": Output("integrate_adaptive"),
        "grid": Output("adaptive_grid", ("GRID", "GRIDDED"), ("grid",)),
        "dense": Output("integrate_dense", ("DENSE_OUTPUT", "GRIDDED", "WITH_STAGES"),
                        ("dense_grid",)),
        "section": Output("adaptive_section", ("SECTION",), ("section",)),
        "section_dense": Output("adaptive_section_dense", ("SECTION", "SECTION_DENSE",
                                                           "WITH_STAGES"), ("dense_section",)),
    }),
}

#: the name Python knows a driver by -> (kind, output)
DRIVER_NAMES = {out.name: (kind, output) for kind, d in DRIVERS.items()
                for output, out in d.outputs.items()}

#: what every fixed-step family binds (the fixed loop, and the partial steps of its time grid)
STEP = ("make_ws", "step")
#: what it binds too under ``sum=compensated`` (the loops call it instead of ``step``)
SUM = ("step_sum",)
#: what a family that runs the adaptive loop binds (templates/adaptive.py, templates/sampling.py)
ADAPTIVE_PART = ("adaptive_ws", "attempt", "attempt_outcome", "controller_init",
                 "controller_state", "controller_clip", "controller_prepare",
                 "controller_accept", "controller_reject", "first_step", "initial_step",
                 "partial_step", "to_tuple_shift", "FSAL", "IORD")
#: what a pair with a continuous extension adds (the dense outputs, ``dense_coeffs``)
DENSE_PART = ("attempt_stages", "dense_from_stages", "dense_eval", "dense_slope", "dense_coeffs",
              "DENSE_NFEV")


@dataclass(frozen=True)
class Family:
    """A family's bindings: its step writer (steps/<module>.py) and, per driver kind it runs on,
    the names that writer defines for the loop (and :data:`SUM` under ``sum=compensated``).
    ``dense``: a pair with a continuous extension binds :data:`DENSE_PART` too."""

    writer: str
    kinds: dict
    dense: bool = False


FAMILIES = {
    "explicit-rk": Family("steps/erk.py", {"fixed": STEP}),
    "embedded-rk": Family("steps/pair.py", {"fixed": STEP, "adaptive": STEP + ADAPTIVE_PART},
                          dense=True),
    "extrapolation": Family("steps/odex.py", {"fixed": STEP, "adaptive": STEP + ADAPTIVE_PART}),
    "implicit-rk": Family("steps/irk.py (steps/prk.py for a singular A)", {"fixed": STEP}),
    "partitioned": Family("steps/partitioned.py", {"fixed": STEP}),
    "composition": Family("steps/partitioned.py (steps/prk.py: a user's basis)", {"fixed": STEP}),
    "partitioned-rk": Family("steps/prk.py", {"fixed": STEP}),
    "splitting": Family("steps/lie_poisson.py", {"fixed": STEP}),
    "generating-function": Family("steps/genfun.py", {"fixed": STEP}),
}


def driver_kind(method) -> str:
    """The driver kind of a compiled method (a MethodConfig): adaptive (option ``adaptive``) or
    fixed step."""
    return "adaptive" if method.base.values.get("adaptive") else "fixed"
