"""External engines as competitor methods: heyoka's Taylor method, rebound's IAS15 and WHFast
(scipy's solve_ivp solvers: :mod:`gnibench.methods.scipy_methods`).

They are not compiled gnibench kernels. Each record carries ``run(problem_bound, values, grid, kernel) ->
EngineRun`` (:mod:`gnibench.methods.engines.heyoka`, :mod:`gnibench.methods.engines.rebound`), and :func:`gnibench.suite.cell.solve.solve` calls it
instead of the compiled driver. The output has the same columns as any other method (t, states, err_<I>, global_error,
steps, nfev).

**Sampling.** A fixed-step method with step h, sampled every K steps, gives rows at t = k·K·h plus
the final point. The adaptive engines choose their own steps. For them, the option ``dt_out`` plays
the role of h for the output grid only: ``--steps N`` means N intervals of dt_out, ``--t-end T``
means ceil(T/dt_out) intervals (the last one shortened to land on T), and ``--every K`` keeps every
K-th point. With ``dt_out`` = h they therefore sample exactly the times a fixed-step method
samples. Heyoka fills these samples from its dense output, IAS15 lands on each of them
(``exact_finish_time``). WHFast is fixed-step, so its ``h`` is its real step, as for the compiled
methods.

**Cost columns.** ``steps`` is the engine's own count: heyoka's steps (counted by a step callback),
rebound's ``steps_done``. ``nfev`` is recorded only where it is known. WHFast's default kernel
evaluates the interaction forces once per step, so nfev = steps. heyoka does not evaluate f: a
Taylor step computes order-p series by automatic differentiation. IAS15 does not expose its
predictor-corrector iterations. For these two, nfev is NaN (empty in csv, null in json), and wall
time is the cost to compare.

**Modifiers.** Observer, penalty and projection act on gnibench's compiled vector field, which these
engines never see. Combining them with an external method is refused with a UserError.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from gnibench.methods.base import Method
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.foundation.params import Param

DT_OUT = Param("dt_out", 0.01, "output sampling interval (the engine picks its own steps; "
               "default: 0.01 time scales of the problem)", low=0.0, low_open=True, scaled=True)


def _not_compiled(ctx) -> str:
    raise RuntimeError("external methods run through Method.run, not through compiled kernels")


@dataclass(frozen=True)
class ExternalMethod(Method):
    """A method run by an external engine.

    ``run(problem_bound, values, grid, kernel) -> gnibench.methods.engines.heyoka.EngineRun`` integrates onto the sample grid
    (:class:`gnibench.suite.cell.solve.SampleGrid`); ``kernel`` is the problem's compiled module
    (:func:`gnibench.suite.cell.compiled.problem_kernel`), for engines that call its field. ``grid_param`` names the option that spaces that grid (``h``
    or ``dt_out``). ``requires(problem_record)`` raises a UserError for problems the engine cannot
    take.
    """

    run: Callable | None = None
    kind: str = "external"
    grid_param: str = "h"
    adaptive: bool = False
    engine: str = ""
    requires: Callable | None = None

    def check_structure(self, problem, has_modifiers: bool) -> None:
        if has_modifiers:
            raise UserError(f"method {self.id} runs in the external engine {self.engine}; modifiers "
                            f"(+observer, +penalty, ...) act on gnibench's compiled vector field "
                            f"and apply only to the compiled methods")
        super().check_structure(problem, has_modifiers)
        if self.requires is not None:
            self.requires(problem)

    def describe(self) -> dict:
        d = super().describe()
        d["properties"].update(external=True, adaptive=self.adaptive)
        d["engine"] = self.engine
        return d


def _run_heyoka(problem_bound, values, grid, kernel=None):
    from gnibench.methods.engines.heyoka import heyoka_propagate

    return heyoka_propagate(problem_bound, grid.t, values["precision"], values["tol"])


def _run_ias15(problem_bound, values, grid, kernel=None):
    from gnibench.methods.engines.rebound import rebound_propagate

    return rebound_propagate(problem_bound, grid.t, "ias15", epsilon=values["epsilon"])


def _run_whfast(problem_bound, values, grid, kernel=None):
    from gnibench.methods.engines.rebound import rebound_propagate

    return rebound_propagate(problem_bound, grid.t, "whfast", h=grid.h, step_counts=grid.step,
                             h_last=grid.h_last)


def _heyoka_problem(problem) -> None:
    from gnibench.methods.engines.heyoka import check_heyoka

    check_heyoka(problem)


def _rebound_problem(problem) -> None:
    from gnibench.methods.engines.rebound import adapter

    adapter(problem)


heyoka_taylor = ExternalMethod(
    id="heyoka-taylor", family="external (heyoka)", order=20,
    reference="Biscani & Izzo, MNRAS 501 (2021) 2614; beyond the seeds",
    doc="adaptive Taylor method built from the problem's sympy model. The order depends on tol: "
        "p = ceil(1 - ln(tol)/2), i.e. 20 at the default tol = eps(double), 23 in long double, "
        "40 in real128; 'order' lists the double default and the result meta records p",
    generate=_not_compiled,
    params=(DT_OUT,
            Param("tol", None, "relative and absolute tolerance (default: epsilon of precision)",
                  low=0.0, low_open=True),
            Param("precision", "double", "floating-point type of the integration", kind="str",
                  choices=("double", "long double", "real128"))),
    run=_run_heyoka, grid_param="dt_out", adaptive=True, engine="heyoka", requires=_heyoka_problem,
)

rebound_ias15 = ExternalMethod(
    id="rebound-ias15", family="external (rebound)", order=15,
    reference="Rein & Spiegel, MNRAS 446 (2015) 1424; beyond the seeds",
    doc="IAS15: 15th-order Gauss-Radau predictor-corrector, adaptive step (PRS23 criterion); "
        "N-body problems with a rebound adapter only",
    generate=_not_compiled,
    params=(DT_OUT, Param("epsilon", 1e-9, "IAS15 accuracy parameter (rebound's default)",
                          low=0.0, low_open=True)),
    implicit=True, run=_run_ias15, grid_param="dt_out", adaptive=True, engine="rebound",
    requires=_rebound_problem,
)

rebound_whfast = ExternalMethod(
    id="rebound-whfast", family="external (rebound)", order=2,
    reference="Wisdom & Holman, AJ 102 (1991); Rein & Tamayo, MNRAS 452 (2015); beyond the seeds",
    doc="WHFast: Wisdom-Holman splitting (Kepler drifts in Jacobi coordinates, interaction kicks), "
        "standard 2nd-order kernel, no correctors; exact for a single Kepler orbit; N-body problems "
        "with a rebound adapter only",
    generate=_not_compiled,
    symplectic=True, symmetric=True, run=_run_whfast, grid_param="h", engine="rebound",
    requires=_rebound_problem,
)
