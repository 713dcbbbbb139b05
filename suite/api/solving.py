"""``gnibench.solve``: one cell, as ``gnibench solve`` computes and writes it
(:func:`gnibench.suite.runs.solving.solve_output`: the same table and metadata)."""
from __future__ import annotations

from dataclasses import dataclass, field


@dataclass
class Trajectory:
    """One solved cell. ``samples``: a DataFrame with exactly the columns of ``gnibench solve``'s
    csv (``t``, the states, ``err_<I>``, ``global_error``, ``steps``, ``nfev``, the chosen
    metrics' columns; for ``section=K`` the crossings). ``meta``: the JSON output's ``meta``
    (canonical specs, status, reason, versions, timings, ``metrics``: the per-cell values).
    ``skipped``: chosen metrics that do not apply, with why (the command line prints them)."""

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


def solve(problem, method, *, t_end: float | None = None, steps: int | None = None,
          every: int = 1, dt_out: float | None = None, section: int | None = None,
          metrics=(), reference: str | None = None) -> Trajectory:
    """Integrate one cell, as ``gnibench solve PROBLEM METHOD``. ``problem`` and ``method``:
    spec strings (``"kepler-2d:e=0.6"``, ``"rk4:h=0.01+observer:on=H/L"``) or parsed values;
    exactly one of ``t_end`` and ``steps``; ``every``, ``dt_out``, ``section``, ``reference``,
    ``metrics`` (a list of metric specs, or one comma-separated string) as the options of the
    command line. Bad input raises :class:`gnibench.UserError`; a diverging integration is a
    status (``.status``, ``.reason``), not an exception."""
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
