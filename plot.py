"""``gnibench.plot``: the report's figures for a notebook, as matplotlib figures.

:func:`work_precision`, :func:`invariant_errors`, :func:`global_error` and
:func:`ensemble_work_precision` draw what the report
draws (the same families, names, colours and markers, the same layout and text sizes) from a
:class:`gnibench.RunResult`, a results directory, or the tables themselves (``cells``,
``samples``, ``timings`` DataFrames as ``gnibench run`` writes them). They return a
:class:`matplotlib.figure.Figure` on matplotlib's Agg canvas (no pyplot, no window): show it in
a notebook as the cell's value, or save it with ``fig.savefig(path)``. A family keeps its colour
and marker across the figures of a session, as across the figures of a report.

The options are those of an experiment file's ``[report]`` section, checked the same way: one
:class:`gnibench.UserError` line for a bad one. ``import gnibench.plot`` and the attribute
``gnibench.plot`` are this module; the helpers live in :mod:`gnibench.reports.plot_api` (the
reports' floor of the layout).
"""
from gnibench.reports.plot_api import (ensemble_work_precision, global_error, invariant_errors,
                                       work_precision)

__all__ = ["ensemble_work_precision", "global_error", "invariant_errors", "work_precision"]
