"""Global error: the Euclidean distance of the numerical solution to the reference solution.

[HLW] Fig 2.3 and Table 2.1 (global error of the Kepler problem); the reference is the exact
solution where the problem has one, else heyoka or rebound (:mod:`gnibench.suite.cell.reference`).
"""
from __future__ import annotations

import numpy as np
from gnibench.suite.metrics.base import Metric, MetricOutput, max_abs


def global_errors(traj) -> np.ndarray:
    """|y(t) - y_ref(t)| at every sample (inf where the state overflowed)."""
    with np.errstate(over="ignore", invalid="ignore"):
        return np.sqrt(np.sum((traj.y - traj.reference.y) ** 2, axis=1))


def _compute(traj, problem, values) -> MetricOutput:
    g = global_errors(traj)
    return MetricOutput(columns={"global_error": g},
                        scalars={"final_global_error": float(g[-1]) if len(g) else float("nan"),
                                 "max_global_error": max_abs(g)})


global_error = Metric(
    id="global_error", title="global error against the reference solution",
    reference="[HLW] Fig 2.3, Table 2.1",
    doc="Euclidean norm of y(t) - y_ref(t) at every sample",
    compute=_compute, needs=("reference", "samples"), default=True,
    columns=(("global_error", "|y(t) - y_ref(t)|"),),
    scalars=(("final_global_error", "global error at the last sample"),
             ("max_global_error", "its maximum over the samples; NaN counts as infinite")),
)
