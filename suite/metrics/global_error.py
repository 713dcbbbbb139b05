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
    ref = traj.reference
    acc = ref.error if ref.error is not None else np.full(len(g), np.nan)
    with np.errstate(over="ignore", invalid="ignore"):
        size = float(np.max(np.sqrt(np.sum(ref.y ** 2, axis=1)))) if len(g) else float("nan")
    return MetricOutput(columns={"global_error": g, "reference_error": acc},
                        scalars={"final_global_error": float(g[-1]) if len(g) else float("nan"),
                                 "max_global_error": max_abs(g),
                                 "final_reference_error": float(acc[-1]) if len(g) else
                                 float("nan"),
                                 "max_reference_error": float(np.max(acc)) if len(g) and
                                 not np.isnan(acc).all() else float("nan"),
                                 "solution_size": size})


global_error = Metric(
    id="global_error", title="global error against the reference solution",
    reference="[HLW] Fig 2.3, Table 2.1",
    doc=("Euclidean norm of y(t) - y_ref(t) at every sample, and the reference's own accuracy "
         "estimate there (its distance to the same engine at a 100 times looser tolerance; NaN "
         "for the exact solution)"),
    compute=_compute, needs=("reference", "samples"), default=True,
    columns=(("global_error", "|y(t) - y_ref(t)|"),
             ("reference_error", ("the reference's accuracy estimate at the sample (NaN: exact "
                                  "solution)"))),
    scalars=(("final_global_error", "global error at the last sample"),
             ("max_global_error", "its maximum over the samples; NaN counts as infinite"),
             ("final_reference_error", "the reference's accuracy estimate at the last sample"),
             ("max_reference_error", "its maximum over the samples (the floor of max_global_error)"),
             ("solution_size", "max over the samples of |y_ref|: the scale of a saturated "
                               "global error")),
)
