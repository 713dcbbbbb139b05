"""The typed cell: one problem x method x horizon x sampling, validated once at the edge.

A :class:`CellSpec` is made from spec texts (or typed values) once, where the input arrives (the
command line, an experiment file, the Python API), by :func:`build`: every check of the cell runs
there, before any work (the options, the horizon, the budgets, what applies to which kind of
cell). Then it is passed everywhere else as it is: the driver facade
(:func:`gnibench.suite.cell.driver.integrate`, which dispatches on :attr:`CellSpec.kind` and
checks nothing again), the metrics, the runner's workers (it pickles; its records travel as
references to their registries, :mod:`gnibench.suite.foundation.registries`). Its canonical texts
serve only as keys and for display.

:func:`gnibench.suite.metrics.cells.make_cell` is the edge that also parses metric specs and lays
the grid at whole periods that η(nT) needs (this floor is below the metrics).
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from enum import Enum
from functools import cached_property

from gnibench.suite.cell.calls import COUNTERS
from gnibench.suite.cell.grid import grid, grid_step, sample_rows
from gnibench.suite.cell.reference import ReferenceSpec, default_reference, parse_reference
from gnibench.suite.cell.spec import MethodConfig, prepare
from gnibench.suite.foundation.budgets import check_count, check_integer, check_output
from gnibench.suite.foundation.errors import UserError, named, spelled
from gnibench.suite.foundation.params import Bound

LOCATORS = ("dense", "henon")


class CellKind(str, Enum):
    """How a cell is integrated: the branch of :func:`gnibench.suite.cell.driver.integrate`."""

    FIXED = "fixed step"            # a compiled fixed-step method (also backward, ``reverse``)
    ADAPTIVE = "adaptive"           # a compiled adaptive method (embedded pairs, odex)
    ENGINE = "engine"               # heyoka, rebound, scipy, a user's Python code: Method.run
    TRANSFORMED = "transformed"     # a compiled method on a transformed problem (K-S, [B] (5.4))
    SECTION = "section"             # the crossings of the problem's Poincaré section

    def __str__(self) -> str:
        return self.value


@dataclass(frozen=True)
class CellSpec:
    """A validated cell (made by :func:`build` only).

    Attributes
    ----------
    problem, method:
        The parsed problem (id and option values) and method (base and modifiers with their
        resolved options): :class:`~gnibench.suite.foundation.params.Bound`,
        :class:`~gnibench.suite.cell.spec.MethodConfig`. An external engine's ``dt_out`` is set
        to the cell's grid.
    steps, t_end:
        The horizon as given: exactly one of them.
    every, dt_out, section:
        Sampling: a sample every K steps (or every K-th point of the grid t = k dt_out), or the
        first ``section`` crossings of the problem's Poincaré section.
    reference, reference_given:
        What ``global_error`` is measured against (None: nothing), and whether it was chosen
        (else it is the problem's default: its exact solution where it has one).
    metrics:
        The chosen metrics (:class:`gnibench.suite.metrics.base.MetricChoice`), beside the
        default ones.
    nsteps, h_last:
        The horizon, computed once: ``nsteps`` steps of ``h``, the last one ``h_last``
        (:func:`gnibench.suite.cell.grid.grid`); for an adaptive method, the grid of its ``h``.
    reverse:
        Integrate backward in time (steps of -h; fixed-step compiled methods), e.g. to check
        that a symmetric method retraces its steps, Φ_{-h} ∘ Φ_h = id ([HLW] (1.7)).
    locator:
        How section crossings are located: None (dense output where it applies, else Hénon's
        trick), ``dense`` or ``henon`` (:mod:`gnibench.suite.cell.sections`).
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
    nsteps: int = 0
    h_last: float = 0.0
    reverse: bool = False
    locator: str | None = None

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

    # -- what kind of cell ------------------------------------------------------------------------

    @property
    def method_kind(self) -> str:
        """How the method runs: ``compiled``, ``external`` or ``python`` (``Method.kind``)."""
        return self.method.kind

    @cached_property
    def transformed(self) -> Bound | None:
        """The transformed problem a compiled method integrates (K-S), or None."""
        return self.problem.record.transformed(self.problem.values)

    @property
    def adaptive(self) -> bool:
        """A compiled method in adaptive mode (option ``adaptive``)."""
        return bool(self.method.base.values.get("adaptive"))

    @property
    def kind(self) -> CellKind:
        """The branch of the driver facade that integrates this cell."""
        if self.section is not None:
            return CellKind.SECTION
        if self.method_kind != "compiled":
            return CellKind.ENGINE
        if self.transformed is not None:
            return CellKind.TRANSFORMED
        return CellKind.ADAPTIVE if self.adaptive else CellKind.FIXED

    # -- the horizon ------------------------------------------------------------------------------

    @property
    def h(self) -> float:
        """The step that spaces the cell's steps (an adaptive engine's: its dt_out)."""
        return grid_step(self.method)

    @property
    def t_final(self) -> float:
        """The end of the horizon: ``t_end``, or ``nsteps`` steps."""
        return (self.nsteps - 1) * self.h + self.h_last

    @cached_property
    def grid_spacing(self) -> float | None:
        """The spacing of a compiled cell's time grid: ``dt_out``, or the method option dt_out
        of dopri5/dop853 (:func:`gnibench.suite.cell.timegrid.effective_dt_out`)."""
        from gnibench.suite.cell.timegrid import effective_dt_out

        return effective_dt_out(self.method, self.dt_out)

    @cached_property
    def grid_plan(self):
        """How a compiled cell is sampled on its time grid
        (:class:`~gnibench.suite.cell.timegrid.GridPlan`: driver, locator, grid points), None
        without one; a transformed problem's grid is in its time component."""
        spacing = self.grid_spacing
        if spacing is None or self.method_kind != "compiled" or self.section is not None:
            return None
        from gnibench.suite.cell.timegrid import plan

        target, tcomp = self.problem, -1
        if self.transformed is not None:
            target = self.transformed
            tcomp = target.record.state.index(self.problem.record.transform.time)
        return plan(target, self.method, spacing, self.t_end if self.adaptive else self.t_final,
                    tcomp)

    @property
    def rows(self) -> int:
        """Samples of a cell sampled every K steps: t = 0, every K-th step and the last one."""
        return sample_rows(self.nsteps, self.every)

    def samples_cell(self) -> CellSpec:
        """The same cell sampled at every step, without a section (what the crossings of an
        engine or a transformed problem are scanned from)."""
        return replace(self, section=None, every=1, reference=None, reference_given=False,
                       locator=None)


def build(problem, method, *, steps: int | None = None, t_end: float | None = None,
          every: int = 1, dt_out: float | None = None, section: int | None = None,
          reference=None, metrics: tuple = (), prepared: bool = False, reverse: bool = False,
          locator: str | None = None) -> CellSpec:
    """A validated cell from texts or typed values (raises UserError, before any work).

    ``reference``: a reference spec text (``exact``, ``heyoka:precision=...``, ``none``), a
    :class:`~gnibench.suite.cell.reference.ReferenceSpec`, or None for the problem's default;
    ignored for a section cell. ``metrics``: chosen metrics, already parsed. ``prepared``: the
    problem and method come from :func:`~gnibench.suite.cell.spec.prepare` for this cell.
    ``reverse``, ``locator``: see :class:`CellSpec`."""
    from gnibench.suite.cell.timegrid import check_dt_out, engine_method

    if not prepared:
        problem, method = prepare(problem, method)
    check_integer(every, "--every")
    dt_out = check_dt_out(dt_out)
    if steps is not None and t_end is not None or steps is None and t_end is None:
        raise UserError(f"give exactly one of {named('--steps', 'N')} or {named('--t-end', 'T')}")
    t_end = None if t_end is None else float(t_end)
    if dt_out is not None and method.kind != "compiled":   # an engine's dt_out: its own grid
        method = engine_method(method, dt_out, problem)
    nsteps, h_last = grid(grid_step(method), steps, t_end)
    if section is not None:
        ref = None
    elif reference is None:
        ref = default_reference(problem.record)
    else:
        text = reference.text() if isinstance(reference, ReferenceSpec) else reference
        ref = parse_reference(text, problem.record)
    cell = CellSpec(problem, method, steps, t_end, every, dt_out, section, ref,
                    reference is not None and section is None, tuple(metrics), nsteps, h_last,
                    bool(reverse), locator)
    _check_kind(cell)
    check_budgets(cell)
    return cell


def _check_kind(cell: CellSpec) -> None:
    """What applies to which kind of cell (section, engine, transformed, adaptive, reverse)."""
    method, problem = cell.method, cell.problem
    compiled = cell.method_kind == "compiled"
    grid_spacing = cell.grid_spacing if compiled else None   # refuses a conflicting method dt_out
    if cell.section is not None:
        from gnibench.suite.cell.sections import section_of

        check_integer(cell.section, "--section")
        section_of(problem.record)                          # a UserError without a section
        if grid_spacing is not None or cell.dt_out is not None:
            raise UserError(f"{spelled('--dt-out')} (or the method option dt_out) does not apply "
                            f"with {spelled('--section')} (the section points are written)")
        _check_locator(cell)
    elif cell.locator is not None:
        raise UserError(f"locator={cell.locator!r} applies to section crossings only; allowed: "
                        f"a section ({named('--section', 'K')}), or no locator")
    if not compiled and cell.transformed is not None:
        raise UserError(f"{method.base.id} is an external engine; it cannot integrate the "
                        f"transformed system of {problem.id} (drop the transform option)")
    if compiled and cell.adaptive and cell.t_end is None:
        raise UserError(f"{method.base.id} with adaptive=true needs {named('--t-end', 'T')} (not "
                        f"{spelled('--steps')}); "
                        f"for fixed steps use {method.base.id}:adaptive=false,h=...")
    if compiled and cell.transformed is not None and grid_spacing is not None:
        tr = problem.record.transform
        if tr.time is None:
            raise UserError(f"bad {spelled('--dt-out')} for {problem.id} with {tr.option}=true: "
                            f"the transformed system has no time component; allowed: "
                            f"{named('--every', 'K')}")
    if compiled and cell.section is None:
        cell.grid_plan                                      # noqa: B018 (planned now, once)
    if cell.reverse:
        if not compiled or cell.adaptive or cell.transformed is not None:
            raise UserError(f"reverse=True applies to fixed-step compiled methods; "
                            f"{method.text()} on {problem.text()} is not one")
        if cell.dt_out is not None or cell.section is not None:
            raise UserError(f"reverse=True samples every K steps; drop {spelled('--dt-out')} and "
                            f"{spelled('--section')}")


def _check_locator(cell: CellSpec) -> None:
    from gnibench.suite.cell.compiled import dense_output_refusal

    if cell.locator not in (None, *LOCATORS):
        raise UserError(f"bad locator {cell.locator!r}; allowed: {', '.join(LOCATORS)}")
    if cell.locator != "dense":
        return
    if cell.method_kind != "compiled" or cell.transformed is not None:
        raise UserError("dense output does not locate these crossings: external engine or "
                        "transformed problem")
    why = dense_output_refusal(cell.problem, cell.method)
    if why:
        raise UserError(f"dense output does not locate these crossings: {why}")


def check_budgets(cell: CellSpec) -> None:
    """Refuse, before any work, a cell beyond the budgets (:mod:`gnibench.suite.foundation.budgets`):
    steps of a fixed-step method, output rows and their memory."""
    problem, method = cell.problem, cell.method
    columns = problem.record.dim + COUNTERS + 1             # the state, the counters and t
    compiled = cell.method_kind == "compiled"
    what = f"{problem.text()} {method.text()}"
    if cell.adaptive:
        check_count(method.base.values["max_steps"], what + " (max_steps)", "GNIBENCH_MAX_STEPS",
                    "steps")
    elif cell.method_kind != "external":
        check_count(cell.nsteps, what, "GNIBENCH_MAX_STEPS", "steps")
    if cell.section is not None:
        check_output(cell.section, columns, what)
        if not compiled or cell.transformed is not None:        # scanned from every step
            check_output(cell.nsteps + 2, columns, what)
        return
    spacing = cell.grid_spacing if compiled and cell.transformed is None else None
    t_final = cell.t_end if cell.t_end is not None else cell.t_final
    if cell.transformed is not None and cell.dt_out:   # a grid in the original time (K-S)
        check_output(t_final / cell.dt_out / cell.every + 2, columns, what)
    if spacing is not None and (not cell.adaptive or cell.t_end is not None):
        check_output(t_final / spacing / cell.every + 2, columns, what)
    elif not cell.adaptive:
        check_output(cell.nsteps / cell.every + 2, columns, what)
