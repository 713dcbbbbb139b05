"""The cell of an experiment: a typed cell placed in its experiment (id, group, label).

:class:`Cell` is the unit of work of the runner (:mod:`gnibench.suite.runs.cellwork`); it pickles
to the workers as it is (:mod:`gnibench.suite.foundation.registries`).
"""
from __future__ import annotations

from dataclasses import dataclass

from gnibench.suite.cell.cellspec import CellSpec


@dataclass(frozen=True)
class Cell:
    """One problem x method x horizon of an experiment: the unit of work of the runner.

    ``spec`` is the typed cell (:class:`~gnibench.suite.cell.cellspec.CellSpec`: the parsed
    problem and method, horizon, sampling, reference solution and chosen metrics), made once when
    the experiment is read; ``id``, ``group`` and ``label`` place it in the experiment. The other
    attributes are the canonical texts and numbers the tables show: ``problem``/``method`` the
    canonical specs, ``metrics`` the canonical texts of the chosen metrics (beside the default
    ones), ``reference`` the canonical text of the chosen reference solution (``exact``,
    ``heyoka:precision=...,tol=...``, ``rebound:tol=...`` or ``none``), None for the default (the
    exact solution where the problem has one).

    ``swept``: the base-method options the cell's group sweeps (a work-precision curve runs
    along them: ``("h",)``, ``("rtol", "atol")`` for a paired sweep), None when the group sweeps
    none (then the cell's own step or tolerance option, :attr:`sweep`). ``repeat``: how many
    times its timed integration runs (:mod:`gnibench.suite.runs.cellwork`).
    """

    id: int
    group: int
    label: str
    spec: CellSpec
    swept: tuple[str, ...] | None = None
    repeat: int = 1
    ensemble: object = None         # an EnsembleSpec (suite/runs/ensembles.py): its orbits

    @property
    def problem(self) -> str:
        return self.spec.problem_text

    @property
    def method(self) -> str:
        return self.spec.method_text

    @property
    def method_kind(self) -> str:
        return self.spec.method_kind

    @property
    def h(self) -> float:
        return self.spec.h

    @property
    def steps(self) -> int | None:
        return self.spec.steps

    @property
    def t_end(self) -> float | None:
        return self.spec.t_end

    @property
    def every(self) -> int:
        return self.spec.every

    @property
    def nsteps(self) -> int:
        return self.spec.nsteps

    @property
    def t_final(self) -> float:
        return self.spec.t_final

    @property
    def metrics(self) -> tuple[str, ...]:
        return self.spec.metric_texts

    @property
    def dt_out(self) -> float | None:
        """The time grid (suite/cell/timegrid.py); the specs stay as given, but for an engine's."""
        return self.spec.dt_out

    @property
    def reference(self) -> str | None:
        return self.spec.reference_text

    @property
    def section(self) -> int | None:
        """Crossings of the problem's Poincaré section (suite/cell/sections.py)."""
        return self.spec.section

    @property
    def sweep(self) -> tuple[str, ...]:
        """The options along which this cell's family runs: :attr:`swept`, else the first of h
        (fixed step only), rtol, tol, epsilon the method spec gives (none: an empty tuple)."""
        if self.swept is not None:
            return self.swept
        from gnibench.suite.cell.spec import structure

        given = structure(self.method).base.given
        adaptive = bool(self.spec.method.base.values.get("adaptive")) or \
            bool(getattr(self.spec.method.base.record, "adaptive", False))
        return next(((k,) for k in ("h", "rtol", "tol", "epsilon") if k in given
                     and not (k == "h" and adaptive)), ())

    @property
    def setup_method(self) -> str:
        """The canonical method spec without the options of :attr:`sweep`: with the problem,
        horizon, sampling and reference, what the cells of one family share
        (:func:`gnibench.suite.metrics.families.setup_key`)."""
        from gnibench.suite.cell.spec import structure

        return structure(self.method).without(*self.sweep).text()

    def described(self) -> dict:
        """What the tables' metadata records of the cell (and a redraw compares)."""
        return {"cell": self.id, "problem": self.problem, "method": self.method,
                "steps": self.steps, "t_end": self.t_end, "every": self.every,
                "dt_out": self.dt_out, "reference": self.reference, "section": self.section}
