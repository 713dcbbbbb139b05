"""Choosing metrics (spec syntax) and applying them to a trajectory."""
from __future__ import annotations

from gnibench.suite.cell.spec import parse_item, parse_problem
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
    return MetricChoice(metric, bind(metric.params, given, f"metric {name}"))


def parse_metrics(texts) -> tuple[MetricChoice, ...]:
    """A list of metric specs (or one comma-separated string of ids without options)."""
    if isinstance(texts, str):
        texts = _split(texts)
    choices = tuple(parse_metric(t) for t in texts)
    ids = [c.text() for c in choices]
    for i, x in enumerate(ids):
        if x in ids[:i]:
            raise UserError(f"metric {x!r} chosen twice; allowed: each metric once")
    return choices


def _split(text: str) -> list[str]:
    """Split ``eta,growth:of=H,window=1/2,precession`` at the commas that start a new metric
    (a comma followed by an id that is not followed by ``=``)."""
    parts: list[str] = []
    for piece in text.split(","):
        piece = piece.strip()
        if parts and "=" in piece.split(":")[0]:
            parts[-1] += "," + piece          # an option of the previous metric
        elif piece:
            parts.append(piece)
    return parts


def selected(choices=()) -> list[MetricChoice]:
    """The default metrics, then the chosen ones (a chosen default is not repeated)."""
    chosen = list(choices)
    ids = {c.metric.id for c in chosen}
    defaults = [MetricChoice(m, bind(m.params, {}, m.id)) for m in METRICS.values()
                if m.default and m.id not in ids]
    return defaults + chosen


def apply(traj, choices=(), problem=None) -> tuple[MetricOutput, dict[str, str]]:
    """Compute the default and chosen metrics of one trajectory.

    ``problem`` is the parsed problem; by default it is parsed back from the trajectory's
    canonical spec. Returns the merged outputs and, for each chosen metric that does not apply,
    why (default metrics that do not apply are skipped silently, e.g. global error without a
    reference).
    """
    if problem is None:
        problem = parse_problem(traj.problem)
    out, skipped = MetricOutput(), {}
    explicit = {c.metric.id for c in choices}
    for choice in selected(choices):
        why = choice.metric.why_not(traj, problem)
        if why:
            if choice.metric.id in explicit:
                skipped[choice.text()] = why
            continue
        out.update(choice.metric.compute(traj, problem, choice.values))
    return out, skipped
