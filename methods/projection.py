"""Orthogonal projection onto the level set after every step: the modern competitor of the observer
(beyond the seeds; HNW GNI IV.4, Algorithm 4.2, "standard projection").

After a step gives ỹ, find y = ỹ + D_H(ỹ)ᵀ λ with H(y) = H0 for the chosen integrals, by simplified
Newton: D_H(ỹ) D_H(ỹ)ᵀ Δλ = H0 − H(y_k). The q x q system is solved by an unrolled Cholesky
factorisation (factored once per step). Iterations stop at round-off (as for Newton in
methods/assembly/templates/newton.py); no convergence in ``maxit`` iterations is status ``newton_failed``.
"""
from __future__ import annotations

from gnibench.methods.base import Modifier
from gnibench.methods.assembly.steps.modifiers import write_projection
from gnibench.methods.modifiers import _resolve
from gnibench.suite.foundation.params import Param

_PARAMS = (
    Param("on", None, "integrals to project on (default: all of the problem's)", kind="names"),
    Param("H0", None, "target values (default: at the initial point)", kind="floats"),
    Param("maxit", 20, "maximum simplified-Newton iterations per step", kind="int", low=1,
          high=1000, show_default=False),
)


def _runtime(values, h0_at_start):
    h0 = values["H0"] if values["H0"] is not None else tuple(h0_at_start)
    return tuple(float(x) for x in h0)


projection = Modifier(
    id="projection", reference="beyond the seeds: HNW GNI IV.4 (standard projection)",
    doc="orthogonal projection of each step onto the level set of the chosen integrals",
    params=_PARAMS, resolve=_resolve("projection"), generate=write_projection, runtime=_runtime,
    runtime_size=lambda values: len(values["on"]), needs_independent=True, kind="step")
