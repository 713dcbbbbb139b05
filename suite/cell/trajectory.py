"""The record of one integrated cell: what every way of integrating gives back.

:func:`gnibench.suite.cell.driver.integrate` returns a :class:`Trajectory` for every kind of cell
(fixed step, adaptive, dense output on a time grid, Poincaré section crossings, external engines,
transformed problems, the benchmark loop). Metrics (:mod:`gnibench.suite.metrics`) are functions of
it; tables, figures and reports read the metrics' outputs.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from gnibench.suite.foundation.status import Status


@dataclass
class ReferenceSamples:
    """The reference solution at the trajectory's sample times (not only its distance).

    ``y`` has the shape of ``Trajectory.y``; ``describe`` says what it is (backend, precision,
    tolerance, whether it came from the disk cache, seconds it took); ``error`` its own accuracy
    estimate at each sample (:func:`gnibench.suite.cell.reference.reference_accuracy`; None for
    the exact solution).
    """

    y: np.ndarray
    describe: dict
    error: np.ndarray | None = None


@dataclass
class Trajectory:
    """One integrated cell: samples, cost counters, status and provenance.

    Attributes
    ----------
    problem, method:
        Canonical specs (they parse back to the same configuration).
    kind:
        ``samples`` (every K steps, or a time grid, plus the final point) or ``section`` (the
        located crossings of the problem's Poincaré section; ``chart`` then holds the chart of
        each point for multi-chart sections such as [B] §7's Γ1..Γ8).
    t, y:
        Sample times and states, shape (rows,) and (rows, N), in the problem's own variables
        (a transformed problem's samples are mapped back, [B] (5.4)).
    steps, nfev, njev, rejected:
        Cumulative counters at each sample: accepted steps, evaluations of the vector field,
        Jacobian evaluations, rejected steps (adaptive methods). ``nfev`` is NaN where an engine
        does not expose it (heyoka, IAS15). It includes the partial steps of a time grid and the
        locators' evaluations of section crossings (whose counters are those of the step that
        holds the crossing). ``steps`` is int64, or float64 with NaN where the method does not
        report it (a user's Python solver: missing in the tables).
    integral_names, integrals, H0:
        The problem's first integrals I_k(y) at every sample, and I_k(y0).
    status, reason:
        How the integration ended (:class:`~gnibench.suite.foundation.status.Status`) and why,
        in words, when it is not ``ok``.
    reference:
        The reference solution at the sample times, or None (no exact solution and none asked).
    provenance:
        Everything needed to re-run and to judge the cell: versions, seed, step size, horizon and
        sampling, H0, engine details, locator of section crossings, compile and wall seconds.
    """

    problem: str
    method: str
    state_names: tuple[str, ...]
    t: np.ndarray
    y: np.ndarray
    steps: np.ndarray
    nfev: np.ndarray
    njev: np.ndarray
    rejected: np.ndarray
    integral_names: tuple[str, ...]
    integrals: np.ndarray
    H0: tuple[float, ...]
    y0: tuple[float, ...]
    status: Status
    reason: str = ""
    kind: str = "samples"
    chart: np.ndarray | None = None
    reference: ReferenceSamples | None = None
    provenance: dict = field(default_factory=dict)

    @property
    def wall_seconds(self) -> float:
        """Integration time (compilation and output excluded)."""
        return float(self.provenance.get("wall_seconds", float("nan")))

    @property
    def compile_seconds(self) -> float:
        """Compiling or loading the cell's kernels from the disk cache, plus one warm-up step."""
        return float(self.provenance.get("compile_seconds", float("nan")))

    @property
    def rows(self) -> int:
        return len(self.t)
