"""The typed cell: one problem x method x horizon x sampling, parsed once at the edge.

A :class:`CellSpec` is made from spec texts (or typed values) once, where the input arrives (the
command line, an experiment file, the Python API), validated before any work, and then passed
everywhere else as it is: the driver facade, the metrics, the runner's workers (it pickles; its
records travel as references to their registries, :mod:`gnibench.suite.foundation.registries`).
Its canonical texts serve only as keys and for display.

:func:`build` makes one from a problem and a method, with the metric choices already made (this
floor is below the metrics); :func:`gnibench.suite.metrics.cells.make_cell` is the edge that also
parses metric specs and lays the grid at whole periods that η(nT) needs.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

from gnibench.suite.cell.grid import grid, grid_step
from gnibench.suite.cell.reference import ReferenceSpec, default_reference, parse_reference
from gnibench.suite.cell.spec import MethodConfig, prepare
from gnibench.suite.foundation.budgets import check_integer
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.foundation.params import Bound


@dataclass(frozen=True)
class CellSpec:
    """A validated cell.

    Attributes
    ----------
    problem, method:
        The parsed problem (id and option values) and method (base and modifiers with their
        resolved options): :class:`~gnibench.suite.foundation.params.Bound`,
        :class:`~gnibench.suite.cell.spec.MethodConfig`. An external engine's ``dt_out`` is set
        to the cell's grid.
    steps, t_end:
        The horizon: exactly one of them.
    every, dt_out, section:
        Sampling: a sample every K steps (or every K-th point of the grid t = k dt_out), or the
        first ``section`` crossings of the problem's Poincaré section.
    reference, reference_given:
        What ``global_error`` is measured against (None: nothing), and whether it was chosen
        (else it is the problem's default: its exact solution where it has one).
    metrics:
        The chosen metrics (:class:`gnibench.suite.metrics.base.MetricChoice`), beside the
        default ones.
    """

    problem: Bound
    method: MethodConfig
    steps: int | None = None
    t_end: float | None = None
    every: int = 1
    dt_out: float | None = None
    section: int | None = None
    reference: ReferenceSpec | None = None
    reference_given: bool = False
    metrics: tuple = ()

    # -- canonical texts (keys and display) -------------------------------------------------------

    @cached_property
    def problem_text(self) -> str:
        return self.problem.text()

    @cached_property
    def method_text(self) -> str:
        return self.method.text()

    @property
    def reference_text(self) -> str | None:
        """The chosen reference's canonical text (``none`` for none); None for the default."""
        if not self.reference_given:
            return None
        return "none" if self.reference is None else self.reference.text()

    @property
    def metric_texts(self) -> tuple[str, ...]:
        return tuple(c.text() for c in self.metrics)

    # -- the horizon ------------------------------------------------------------------------------

    @property
    def kind(self) -> str:
        """How the method runs: ``compiled``, ``external`` or ``python``."""
        return self.method.kind

    @property
    def h(self) -> float:
        """The step that spaces the cell's steps (an adaptive engine's: its dt_out)."""
        return grid_step(self.method)

    @property
    def nsteps(self) -> int:
        return grid(self.h, self.steps, self.t_end)[0]

    @property
    def t_final(self) -> float:
        n, h_last = grid(self.h, self.steps, self.t_end)
        return (n - 1) * self.h + h_last


def build(problem, method, *, steps: int | None = None, t_end: float | None = None,
          every: int = 1, dt_out: float | None = None, section: int | None = None,
          reference=None, metrics: tuple = (), prepared: bool = False) -> CellSpec:
    """A validated cell from texts or typed values (raises UserError, before any work).

    ``reference``: a reference spec text (``exact``, ``heyoka:precision=...``, ``none``), a
    :class:`~gnibench.suite.cell.reference.ReferenceSpec`, or None for the problem's default;
    ignored for a section cell. ``metrics``: chosen metrics, already parsed. ``prepared``: the
    problem and method come from :func:`~gnibench.suite.cell.spec.prepare` for this cell."""
    from gnibench.suite.cell.driver import check_budgets
    from gnibench.suite.cell.sections import section_of
    from gnibench.suite.cell.timegrid import check_dt_out, effective_dt_out, engine_method

    if not prepared:
        problem, method = prepare(problem, method)
    check_integer(every, "--every")
    dt_out = check_dt_out(dt_out)
    if steps is not None and t_end is not None or steps is None and t_end is None:
        raise UserError("give exactly one of --steps N or --t-end T")
    t_end = None if t_end is None else float(t_end)
    if section is not None:
        check_integer(section, "--section")
        section_of(problem.record)                          # a UserError without a section
        if dt_out is not None:
            raise UserError("--dt-out (or the method option dt_out) does not apply with "
                            "--section (the section points are written)")
    if dt_out is not None and method.kind != "compiled":   # an engine's dt_out: its own grid
        method = engine_method(method, dt_out, problem)
    elif dt_out is not None:
        effective_dt_out(method, dt_out)                     # refuses a conflicting method option
    grid(grid_step(method), steps, t_end)
    check_budgets(problem, method, steps, t_end, every, section, dt_out)
    given = reference is not None and section is None
    if section is not None:
        ref = None
    elif reference is None:
        ref = default_reference(problem.record)
    elif isinstance(reference, ReferenceSpec):
        ref = parse_reference(reference.text(), problem.record)
    else:
        ref = parse_reference(reference, problem.record)
    return CellSpec(problem, method, steps, t_end, every, dt_out, section, ref, given,
                    tuple(metrics))
