"""Choosing metrics (spec syntax), applying them to a trajectory, and the sampling they need."""
from __future__ import annotations

from gnibench.suite.cell.spec import parse_item, parse_problem, split_list
from gnibench.suite.foundation.errors import UserError, unknown
from gnibench.suite.foundation.params import bind
from gnibench.suite.metrics import METRICS
from gnibench.suite.metrics.base import MetricChoice, MetricOutput


def parse_metric(text: str) -> MetricChoice:
    """``id[:key=value,...]`` -> a metric with validated options."""
    name, given = parse_item(text, "metric")
    if name not in METRICS:
        raise unknown("metric", name, METRICS)
    metric = METRICS[name]
    values = bind(metric.params, given, f"metric {name}")
    bad = metric.validate(values) if metric.validate is not None else ""
    if bad:
        raise UserError(f"metric {name}: {bad}")
    return MetricChoice(metric, values)


def parse_metrics(texts) -> tuple[MetricChoice, ...]:
    """A list of metric specs or choices (or one comma-separated string of them, as
    ``--metrics`` gives it)."""
    if isinstance(texts, str):
        texts = split_list(texts, "--metrics")
    choices = tuple(t if isinstance(t, MetricChoice) else parse_metric(t) for t in texts)
    ids = [c.metric.id for c in choices]
    for i, x in enumerate(ids):
        if x in ids[:i]:
            raise UserError(f"metric {x!r} chosen twice; allowed: each metric once (one choice "
                            f"takes lists, e.g. growth:of=H/L/global)")
    return choices


def selected(choices=()) -> list[MetricChoice]:
    """The default metrics, then the chosen ones (a chosen default is not repeated)."""
    chosen = list(choices)
    ids = {c.metric.id for c in chosen}
    defaults = [MetricChoice(m, bind(m.params, {}, m.id)) for m in METRICS.values()
                if m.default and m.id not in ids]
    return defaults + chosen


def apply(traj, choices=(), problem=None, families: bool = True) -> tuple[MetricOutput,
                                                                          dict[str, str]]:
    """Compute the default and chosen metrics of one trajectory.

    ``problem`` is the parsed problem (the typed cell's); without it, it is parsed back from the
    trajectory's canonical spec (a trajectory made outside a typed cell). Returns the merged outputs and, for each chosen metric that does not apply,
    why (default metrics that do not apply are skipped silently, e.g. global error without a
    reference). A family metric (or an ensemble metric) never applies to one trajectory: with
    ``families`` it is reported as such (``gnibench solve``), without it is left silently to the
    runner, which computes it across cells (over an ensemble cell's orbits).
    """
    if problem is None:
        problem = parse_problem(traj.problem)
    out, skipped = MetricOutput(), {}
    explicit = {c.metric.id for c in choices}
    for choice in selected(choices):
        if choice.metric.scope in ("family", "ensemble") and not families:
            continue
        why = choice.metric.why_not(traj, problem, choice.values)
        if why:
            if choice.metric.id in explicit:
                skipped[choice.text()] = why
            continue
        out.update(choice.metric.compute(traj, problem, choice.values))
    return out, skipped


def not_applicable(choices, problem) -> dict[str, str]:
    """For each chosen metric that cannot apply to any cell of ``problem`` (a parsed problem),
    why; metrics that may apply (their trajectory checks come later) are left out."""
    out = {}
    for choice in choices:
        why = choice.metric.problem_why_not(problem, choice.values)
        if why:
            out[choice.text()] = why
    return out


def sampling_needs(choices, problem) -> dict[str, float]:
    """How a cell must be sampled for its chosen metrics: ``{"dt_out": T}`` when a metric needs
    samples at whole periods t = nT (η(nT), [B] §5.2) and the problem has a period T; else ``{}``.

    The driver facade's ``dt_out`` grid (or, for a fixed-step method whose h divides T, ``every``
    = :func:`steps_per_period`) gives those samples; a metric that finds none says so. T is the
    period in t, also for a transformed problem (K-S), whose integration variable is not t (see
    :mod:`gnibench.suite.metrics.position_in_orbit`).
    """
    period = getattr(problem.record, "period", None)
    if period is None or not any("period" in c.metric.needs for c in choices):
        return {}
    return {"dt_out": float(period(problem.values))}


def steps_per_period(h: float, period: float, rtol: float = 1e-9) -> int | None:
    """N when N steps of h make one period T (to ``rtol``), else None: ``every = N`` then samples
    a fixed-step cell at every whole period."""
    n = round(period / h)
    return n if n >= 1 and abs(n * h - period) <= rtol * period else None


def period_grid(choices, problem, method, every: int = 1, dt_out: float | None = None):
    """The time grid a cell runs on, given its chosen metrics: ``dt_out`` when one is given;
    else the period T when a metric needs samples at whole periods (η(nT), [B] §5.2) and the
    cell's own samples do not fall on them (a fixed-step method with N steps per period and
    ``every`` dividing N, or a multiple of N, keeps its grid); else None. ``gnibench solve --metrics eta`` and an
    experiment group with ``eta`` and no ``dt_out`` both sample at t = nT this way."""
    from gnibench.suite.cell.grid import grid_step

    if dt_out is not None:
        return dt_out
    needs = sampling_needs(choices, problem)
    if not needs:
        return None
    period = needs["dt_out"]
    v = method.base.values
    external = method.kind == "external"
    transformed = problem.record.transformed(problem.values) is not None
    if not (v.get("adaptive") or external or transformed):
        n = steps_per_period(grid_step(method), period)
        if n is not None and (n % every == 0 or every % n == 0):   # samples fall on t = nT
            return None
    return period
