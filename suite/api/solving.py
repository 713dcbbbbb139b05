"""``gnibench.solve``: one cell, as ``gnibench solve`` computes and writes it
(:func:`gnibench.suite.runs.solving.solve_output`: the same table and metadata)."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from gnibench.suite.api.arguments import api_function

if TYPE_CHECKING:
    from gnibench.suite.cell.spec import MethodConfig
    from gnibench.suite.foundation.params import Bound


@dataclass
class Trajectory:
    """One solved cell (:func:`gnibench.solve`).

    Attributes
    ----------
    samples : pandas.DataFrame
        Exactly the columns of ``gnibench solve``'s csv: ``t``, the states, ``err_<I>`` (the
        error of each first integral), ``global_error``, ``steps``, ``nfev``, then the chosen
        metrics' columns; for ``section=K``, the crossings.
    meta : dict
        The JSON output's ``meta``: canonical specs, ``status``, ``reason``, versions, timings,
        ``metrics`` (the per-cell values).
    skipped : dict
        Chosen metrics that do not apply to this cell, with why (the command line prints them).

    Examples
    --------
    >>> import gnibench
    >>> traj = gnibench.solve("pendulum", "stormer-verlet:h=0.1", steps=4)
    >>> traj
    Trajectory(pendulum stormer-verlet:h=0.1: ok, 5 rows)
    >>> traj.status, traj.reason
    ('ok', '')
    >>> list(traj.samples.columns)
    ['t', 'p', 'q', 'err_H', 'global_error', 'steps', 'nfev', 'reference_error']
    """

    samples: object
    meta: dict
    skipped: dict = field(default_factory=dict)

    @property
    def status(self) -> str:
        return self.meta["status"]

    @property
    def reason(self) -> str:
        return self.meta["reason"]

    @property
    def metrics(self) -> dict:
        """The per-cell metric values (``meta["metrics"]``)."""
        return self.meta.get("metrics", {})

    def __repr__(self) -> str:
        return (f"Trajectory({self.meta['problem']} {self.meta['method']}: {self.status}, "
                f"{len(self.samples)} rows)")


@api_function
def solve(problem: str | Bound, method: str | MethodConfig, *, t_end: float | None = None,
          steps: int | None = None, every: int = 1, dt_out: float | None = None,
          section: int | None = None, metrics: str | list[str] = (),
          reference: str | None = None) -> Trajectory:
    """Integrate one cell, as ``gnibench solve PROBLEM METHOD``.

    Parameters
    ----------
    problem : str or parsed problem
        A PROBLEM spec, ``id[:key=value,...]`` (``"kepler-2d:e=0.6"``), or a problem parsed by
        :func:`gnibench.suite.cell.spec.parse_problem`.
    method : str or parsed method
        A METHOD spec, ``base[:key=value,...]{+modifier[:key=value,...]}``
        (``"rk4:h=0.01+observer:on=H/L"``), or a method parsed by
        :func:`gnibench.suite.cell.spec.parse_method`.
    t_end : float, optional
        The final time T (the last step is shortened to land on it). Exactly one of ``t_end``
        and ``steps``.
    steps : int, optional
        The number of steps N of a fixed-step method.
    every : int, default 1
        A sample every K steps (or every K-th point of the ``dt_out`` grid), plus the final
        point.
    dt_out : float, optional
        Samples at t = k dt_out plus the final point, located exactly (dense output or a partial
        step); the steps are those taken without it.
    section : int, optional
        Integrate until K crossings of the problem's Poincaré section (within ``t_end`` or
        ``steps``) and return the crossings.
    metrics : str or list of str, default ()
        Metrics beside the defaults (``err_<I>``, ``global_error``): a list of metric specs or
        one comma-separated string, e.g. ``"eta,growth:of=H"``
        (:func:`gnibench.list_metrics`).
    reference : str, optional
        What ``global_error`` is measured against: ``exact``, ``heyoka[:precision=...,tol=...]``,
        ``rebound[:tol=...]`` or ``none``; default: the exact solution when the problem has one.

    Returns
    -------
    Trajectory
        The samples as a DataFrame (``.samples``), the metadata (``.meta``), the status
        (``.status``, ``.reason``).

    Raises
    ------
    gnibench.UserError
        Bad input (an unknown id, a bad option, a request beyond the budgets), before any work.
        A diverging integration is a status (``.status``, ``.reason``), not an exception.

    Examples
    --------
    >>> import gnibench
    >>> traj = gnibench.solve("kepler-2d:e=0.6", "rk4:h=0.01", t_end=1.0, every=50)
    >>> traj.samples[["t", "steps", "nfev"]]
         t  steps   nfev
    0  0.0      0    0.0
    1  0.5     50  200.0
    2  1.0    100  400.0
    >>> bool(abs(traj.samples["err_H"]).max() < 1e-6)
    True
    """
    from gnibench.suite.cell.user.loader import discover, refresh
    from gnibench.suite.runs.solving import json_meta, solve_cell_spec, solve_output

    discover()                      # GNIBENCH_LOAD and entry points, as `gnibench solve`
    refresh()                       # definitions edited since they were loaded
    out = solve_output(solve_cell_spec(problem, method, steps=steps, t_end=t_end, every=every,
                                       dt_out=dt_out, section=section, reference=reference,
                                       metrics=metrics))
    if out.interrupted is not None:
        raise out.interrupted
    return Trajectory(out.frame, json_meta(out.meta), dict(out.skipped))
