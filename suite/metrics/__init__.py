"""The metric registry: one line per metric. A new metric is one file plus one line here.

See :mod:`gnibench.suite.metrics.base` for the record, :mod:`gnibench.suite.metrics.compute`
for how metrics are chosen and applied, and :mod:`gnibench.suite.metrics.families` for the metrics
computed across the cells of an experiment that differ only in h.
"""
from gnibench.suite.foundation.registries import register
from gnibench.suite.metrics import (
    area,
    global_error,
    growth,
    invariants,
    order,
    pericenter,
    position_in_orbit,
    section_stats,
)

METRICS = {m.id: m for m in (
    invariants.invariant_error,
    invariants.relative_invariant_error,
    global_error.global_error,
    position_in_orbit.position_in_orbit,
    pericenter.precession,
    growth.growth,
    order.order,
    section_stats.section_stats,
    area.area,
)}


def lookup(id: str):
    """The metric record ``id``, or None."""
    return METRICS.get(id)


register("metric", lookup)
