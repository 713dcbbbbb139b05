"""Errors of the first integrals: I_k(y(t)) - I_k(y0), absolute and relative.

[B] §2 measures how far the numerical solution leaves Γ = {H = H0}: the errors of the integrals
err_H(t) = H(y(t)) - H(y0) ([B] Figs 2, 3, 5-14, 27-30, 32; [HLW] Fig 2.3, Table 2.1).
"""
from __future__ import annotations

import numpy as np
from gnibench.suite.metrics.base import Metric, MetricOutput, max_abs


def invariant_errors(traj) -> np.ndarray:
    """I_k(y) - I_k(y0) at every sample, shape (rows, q)."""
    return traj.integrals - np.asarray(traj.H0, dtype=float)[None, :]


def _absolute(traj, problem, values) -> MetricOutput:
    err = invariant_errors(traj)
    out = MetricOutput()
    for k, name in enumerate(traj.integral_names):
        out.columns[f"err_{name}"] = err[:, k]
        out.scalars[f"max_abs_err_{name}"] = max_abs(err[:, k])
        out.scalars[f"scale_{name}"] = abs(float(traj.H0[k]))
    return out


def relative_invariant_errors(traj) -> np.ndarray:
    """(I_k(y) - I_k(y0)) / |I_k(y0)|; NaN for an integral that vanishes at y0."""
    scale = np.abs(np.asarray(traj.H0, dtype=float))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(scale > 0, invariant_errors(traj) / np.where(scale > 0, scale, 1.0), np.nan)


def _relative(traj, problem, values) -> MetricOutput:
    rel = relative_invariant_errors(traj)
    out = MetricOutput()
    for k, name in enumerate(traj.integral_names):
        out.columns[f"relerr_{name}"] = rel[:, k]
        out.scalars[f"max_rel_err_{name}"] = (max_abs(rel[:, k]) if traj.H0[k] != 0
                                              else float("nan"))
    return out


invariant_error = Metric(
    id="invariant_error", title="error of each first integral",
    reference="[B] §2 (distance to Γ), Figs 2-14, 27-32; [HLW] Fig 2.3",
    doc="err_<I> = I(y(t)) - I(y0) at every sample, for every first integral of the problem",
    compute=_absolute, needs=("integrals",), default=True,
    columns=(("err_<I>", "I(y(t)) - I(y0)"),),
    scalars=(("max_abs_err_<I>", ("max over the samples of |I(y) - I(y0)|; NaN counts as "
                                 "infinite")),
             ("scale_<I>", "|I(y0)|: the scale of a saturated error of I")),
)

relative_invariant_error = Metric(
    id="relative_invariant_error", title="relative error of each first integral",
    reference="[B] §5.2 (relative errors of H), [HLW] Table 2.1",
    doc="relerr_<I> = (I(y(t)) - I(y0)) / |I(y0)|; NaN for an integral that vanishes at y0",
    compute=_relative, needs=("integrals",),
    columns=(("relerr_<I>", "(I(y(t)) - I(y0)) / |I(y0)|"),),
    scalars=(("max_rel_err_<I>", "max over the samples of |relerr_<I>|"),),
)
