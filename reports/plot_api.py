"""``gnibench.plot``: the report's figures for a notebook, as matplotlib figures.

:func:`work_precision`, :func:`invariant_errors` and :func:`global_error` draw what the report
draws (the same families, names, colours and markers, the same layout and text sizes,
:mod:`gnibench.reports.render`) from a :class:`gnibench.RunResult`, a results directory, or the
tables themselves (``cells``, ``samples``, ``timings`` DataFrames as ``gnibench run`` writes
them). They return a :class:`matplotlib.figure.Figure` on matplotlib's Agg canvas (no pyplot, no
window): show it in a notebook as the cell's value, or save it with ``fig.savefig(path)``.

A family keeps its colour and marker across the figures of a session, as across the figures of
a report (one :class:`gnibench.reports.palette.Palette` for the module).

The options are those of an experiment file's ``[report]`` section
(:mod:`gnibench.suite.runs.report_schema`), checked the same way: one
:class:`gnibench.UserError` line for a bad one.
"""
from __future__ import annotations

from pathlib import Path

from gnibench.suite.foundation.errors import UserError

__all__ = ["ensemble_work_precision", "global_error", "invariant_errors", "work_precision"]
_PALETTE: list = []


def _palette():
    """The session's palette: a family met again keeps its style."""
    if not _PALETTE:
        from gnibench.reports.palette import Palette

        _PALETTE.append(Palette())
    return _PALETTE[0]


class _Tables:
    """The tables a figure is drawn from (``result``: a RunResult, a results directory, or a
    dict of DataFrames ``cells``, ``samples``, ``timings``), with the report's family columns."""

    def __init__(self, result):
        from gnibench.reports.results import load_results
        from gnibench.reports.setups import add_setups

        samples = None
        if isinstance(result, (str, Path)):
            res = load_results(Path(result))
            cells, timings, samples = res.cells, res.timings, res.samples
        elif isinstance(result, dict) and "cells" in result:
            cells, timings = result["cells"], result.get("timings")
            samples = result.get("samples")
        elif all(hasattr(result, k) for k in ("cells", "samples", "timings")):
            cells, timings, samples = result.cells, result.timings, result.samples
        else:
            raise UserError(f"bad result {type(result).__name__}; allowed: a RunResult, a "
                            f"results directory, or a dict of the tables (cells, samples, "
                            f"timings DataFrames)")
        self.cells = add_setups(cells)
        self.timings = timings
        self._samples = samples

    @property
    def samples(self):
        if callable(self._samples):            # a results directory's, read on demand
            self._samples = self._samples()
        if self._samples is None:
            raise UserError("no samples: give a RunResult, a results directory, or a dict with "
                            "samples (a DataFrame of samples.parquet)")
        return self._samples

    def problem(self, problem: str | None):
        """The cells of one problem (a spec or an id; default: the first problem)."""
        cells = self.cells
        specs = list(dict.fromkeys(cells["problem"].astype(str)))
        if problem is None:
            problem = specs[0]
        mine = cells[(cells["problem"].astype(str) == problem)
                     | (cells["problem_id"].astype(str) == problem)]
        if not len(mine):
            from gnibench.suite.foundation.errors import unknown

            raise unknown("problem", problem, specs)
        return str(mine["problem"].iloc[0]), mine


def _options(**given) -> dict:
    from gnibench.suite.runs.report_schema import report_options

    return report_options({k: v for k, v in given.items() if v is not None},
                          "gnibench.plot").model_dump()


def work_precision(result, *, problem: str | None = None, horizon: float | None = None,
                   measures: list[str] | None = None, costs: list[str] | None = None):
    """The work-precision diagram of one problem and horizon: error against cost, one curve per
    family (the cells of one setup), as in the report.

    Parameters
    ----------
    result : RunResult, path or dict
        A run's result (:func:`gnibench.run`), a results directory, or a dict of the tables
        (``cells`` and ``timings`` DataFrames).
    problem : str, optional
        The problem (a spec or an id); default: the first of the cells.
    horizon : float, optional
        The final time of the cells drawn (one figure holds one horizon and reference, since
        errors over other horizons are not comparable); default: the first cell's.
    measures : list of str, optional
        The errors, one row of panels each: ``final_global_error``, ``max_global_error``,
        ``max_abs_err_<I>``; default: those the cells have (global errors and the first
        integral's).
    costs : list of str, optional
        The cost axes, one column each: ``nfev``, ``wall``; default both.

    Returns
    -------
    matplotlib.figure.Figure
        The figure: families in the report's colours and markers, hollow points below the
        reference's accuracy, the Pareto front dashed, saturation and reference levels in grey.

    Raises
    ------
    gnibench.UserError
        A bad option, an unknown problem, or no cell at that horizon.

    Examples
    --------
    >>> import gnibench
    >>> res = gnibench.run({"name": "wp", "title": "RK4 and DOPRI5", "reference": "none",
    ...                     "t_end": 6.283185307179586, "cells": [
    ...                         {"problems": ["kepler-2d"], "methods": ["rk4"],
    ...                          "vary": {"h": [0.1, 0.05, 0.025]}},
    ...                         {"problems": ["kepler-2d"], "methods": ["dopri5"],
    ...                          "vary": {"rtol": [1e-5, 1e-7, 1e-9], "atol": [1e-5, 1e-7, 1e-9]},
    ...                          "zip": ["rtol", "atol"]}]}, jobs=1)
    >>> fig = gnibench.plot.work_precision(res, costs=["nfev"])
    >>> [ax.get_xlabel() for ax in fig.axes]
    ['f-evaluations (nfev)', 'f-evaluations (nfev)', 'f-evaluations (nfev)']
    >>> sorted(t.get_text() for t in fig.legends[0].get_texts())[:2]
    ['Pareto front (least cost per accuracy)', 'dopri5']
    """
    from gnibench.reports.palette import styles
    from gnibench.reports.plots import brief, problem_id_of
    from gnibench.reports.render import figure
    from gnibench.reports.results import timing_stats
    from gnibench.reports.setups import contexts, family_names
    from gnibench.reports.workprecision import wp_plot

    options = _options(measures=measures, costs=costs)
    tables = _Tables(result)
    name, part = tables.problem(problem)
    chosen = contexts(part)
    if horizon is not None:
        from gnibench.suite.metrics.families import final_time

        want = f"{float(horizon):.12g}"
        chosen = [(n, c) for n, c in chosen
                  if final_time(c.iloc[0].to_dict()) == want]
        if not chosen:
            raise UserError(f"bad horizon {horizon!r}: no cell of {name} ends there")
    context, ctx = chosen[0]
    wall_ms = {c: v[0] * 1e3 for c, v in timing_stats(tables.timings).items()}
    title = f"{brief(name, problem_id_of(name, ctx))}: work-precision" + \
        (f" ({context})" if context else "")
    plot, _ = wp_plot(title, ctx, wall_ms, styles(part, _palette()), family_names(ctx), options)
    if plot is None:
        raise UserError(f"no error measure to draw for {name}: the cells have no global error "
                        f"and no integral error")
    return figure(plot)


def _time_figure(kind: str, result, problem, cells, family, time_axis, error_axis):
    from gnibench.reports.palette import styles
    from gnibench.reports.plots import time_plots
    from gnibench.reports.render import figure

    options = _options(figures=[kind], cells=cells, family=family, time_axis=time_axis,
                       error_axis=error_axis)
    tables = _Tables(result)
    name, part = tables.problem(problem)
    ps = tables.samples[tables.samples["cell"].isin(part["cell"])]
    plots = time_plots(name, part, ps, style=styles(part, _palette()), options=options)
    if not plots:
        raise UserError(f"nothing to draw: the chosen cells of {name} have no "
                        f"{'integral errors' if kind == 'invariants' else 'global error'}")
    return figure(plots[0][1])


def invariant_errors(result, *, problem: str | None = None, cells="auto",
                     family: str | None = None, time_axis: str = "auto",
                     error_axis: str = "log"):
    """The errors of the first integrals against time, one panel per integral, as in the
    report.

    Parameters
    ----------
    result : RunResult, path or dict
        A run's result (:func:`gnibench.run`), a results directory, or a dict of the tables
        (``cells`` and ``samples`` DataFrames).
    problem : str, optional
        The problem (a spec or an id); default: the first of the cells.
    cells : "auto", "all" or list of int, default "auto"
        The cells drawn: all up to 12, else one per family (``"auto"``), all, or these ids.
    family : str, optional
        Only this family's cells (its label, e.g. ``"dop853"``, or its method id).
    time_axis : {"auto", "linear", "log"}, default "auto"
        The t axis ("auto": logarithmic when the samples span two decades).
    error_axis : {"log", "linear"}, default "log"
        The error axis.

    Returns
    -------
    matplotlib.figure.Figure
        ``|I(y(t)) − I(y0)|`` against t; each curve labelled by its family, swept value and cell.

    Raises
    ------
    gnibench.UserError
        A bad option, an unknown problem, or nothing to draw.

    Examples
    --------
    >>> import gnibench
    >>> res = gnibench.run({"name": "sv", "title": "Störmer-Verlet", "reference": "none",
    ...                     "t_end": 10.0, "cells": [{"problems": ["pendulum"],
    ...                     "methods": ["stormer-verlet"], "vary": {"h": [0.1, 0.05]}}]}, jobs=1)
    >>> fig = gnibench.plot.invariant_errors(res, time_axis="linear")
    >>> fig.axes[0].get_ylabel(), fig.axes[0].get_xscale()
    ('|H(y(t)) − H(y0)|', 'linear')
    >>> [t.get_text() for t in fig.legends[0].get_texts()][0].startswith("stormer-verlet h=0.1")
    True
    """
    return _time_figure("invariants", result, problem, cells, family, time_axis, error_axis)


def global_error(result, *, problem: str | None = None, cells="auto",
                 family: str | None = None, time_axis: str = "auto", error_axis: str = "log"):
    """The global error ``|y(t) − y_ref(t)|`` against time, as in the report.

    Parameters
    ----------
    result : RunResult, path or dict
        A run's result (:func:`gnibench.run`), a results directory, or a dict of the tables
        (``cells`` and ``samples`` DataFrames).
    problem : str, optional
        The problem (a spec or an id); default: the first of the cells.
    cells : "auto", "all" or list of int, default "auto"
        The cells drawn: all up to 12, else one per family (``"auto"``), all, or these ids.
    family : str, optional
        Only this family's cells (its label, e.g. ``"dop853"``, or its method id).
    time_axis : {"auto", "linear", "log"}, default "auto"
        The t axis ("auto": logarithmic when the samples span two decades).
    error_axis : {"log", "linear"}, default "log"
        The error axis.

    Returns
    -------
    matplotlib.figure.Figure
        The global error against t; each curve labelled by its family, swept value, cell and
        growth exponent in t.

    Raises
    ------
    gnibench.UserError
        A bad option, an unknown problem, or no cell with a reference.

    Examples
    --------
    >>> import gnibench
    >>> res = gnibench.run({"name": "kepler", "title": "Kepler", "reference": "none",
    ...                     "t_end": 6.283185307179586, "cells": [{"problems": ["kepler-2d"],
    ...                     "methods": ["rk4"], "vary": {"h": [0.1, 0.05]}}]}, jobs=1)
    >>> fig = gnibench.plot.global_error(res, cells=[1])
    >>> fig.axes[0].get_ylabel()
    'global error |y − y_ref|'
    >>> len(fig.axes[0].get_lines())
    1
    """
    return _time_figure("global-error", result, problem, cells, family, time_axis, error_axis)


def ensemble_work_precision(result, *, measure: str | None = None, problem: str | None = None):
    """The statistical work-precision diagram of a run's ensemble cells, as in the report: per
    family, the median over the orbits of an error against the median f-evaluations per orbit,
    a band from the 10 % to the 90 % quantile, and the failure rate beside it
    (:func:`gnibench.reports.ensembles.work_precision`).

    Parameters
    ----------
    result : RunResult or path
        A run with ensemble cells (:func:`gnibench.run`), or its results directory.
    measure : str, optional
        The error, a column of ``ensemble.parquet``; default ``max_global_error`` where there
        is a reference, else the first integral's ``max_abs_err_<I>``.
    problem : str, optional
        The cells of this problem spec only; default all.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (Agg canvas, no pyplot).

    Raises
    ------
    gnibench.UserError
        The run has no ensemble cells, or the measure is not a column of its orbits.

    Examples
    --------
    >>> import gnibench
    >>> res = gnibench.run({"name": "ens", "title": "an ensemble", "reference": "[HLW] I.1",
    ...                     "t_end": 2.0, "cells": [
    ...     {"problems": ["pendulum"], "methods": ["rk4"], "vary": {"h": [0.1, 0.05]},
    ...      "ensemble": {"options": ["q0", "p0"], "sample": "box", "n": 8, "seed": 1,
    ...                   "low": [-1.0, -0.5], "high": [1.0, 0.5]}}]})
    >>> fig = gnibench.plot.ensemble_work_precision(res)
    >>> [ax.get_xlabel() for ax in fig.axes]
    ['f-evaluations per orbit (median)', 'f-evaluations per orbit (median)']
    """
    from gnibench.reports import ensembles
    from gnibench.reports.render import figure

    if isinstance(result, (str, Path)):
        from gnibench.reports.results import load_results, read_table

        path = Path(result)
        if not (path / "ensemble.parquet").is_file():
            raise UserError(f"{path} has no ensemble cells (no ensemble.parquet)")
        cells, orbits = load_results(path).cells, read_table(path / "ensemble.parquet")
        stats = read_table(path / "ensemble_stats.parquet")
    elif getattr(result, "ensemble", None) is not None:
        cells, orbits, stats = result.cells, result.ensemble, result.ensemble_stats
    else:
        raise UserError("this run has no ensemble cells ([cells.ensemble])")
    measure = ensembles.measure_of(orbits, measure)
    return figure(ensembles.work_precision(cells, stats, measure, problem, _palette()))
