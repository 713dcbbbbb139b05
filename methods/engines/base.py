"""What every external engine gives back, and the problem functions engines are judged by.

The engines (:mod:`gnibench.methods.engines.heyoka`, :mod:`gnibench.methods.engines.rebound`) serve
twice: as competitor methods (:mod:`gnibench.methods.external`) and as reference solutions
(:mod:`gnibench.suite.cell.reference`).
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class ProblemFunctions:
    """A problem's generated functions run as plain Python (no compilation), for engine output."""

    names: tuple[str, ...]
    invariants: Callable


def problem_functions(problem) -> ProblemFunctions:
    """The first integrals of a problem record, from the same generated source as the kernels
    (:func:`gnibench.problems.codegen.python_functions`), so external engines are judged by the very
    expressions the compiled methods use."""
    from gnibench.problems.codegen import problem_meta, python_functions

    return ProblemFunctions(tuple(problem_meta(problem)["integrals"]),
                            python_functions(problem)["invariants"])


@dataclass
class EngineRun:
    """What an engine gives back on a sample grid.

    ``y`` is float64; ``y_full`` the same samples in the working precision (None for double).
    ``steps`` is cumulative per sample (integers; float NaN where the engine does not report
    them, as a user's Python solver may not); ``nfev`` cumulative force evaluations, NaN where
    the engine does not expose them; ``njev`` cumulative Jacobian evaluations (None: the engine
    evaluates none). ``status`` is a Status value (``ok``, ``nonfinite``, ...); after a failure
    only the samples reached are kept.
    """

    y: np.ndarray
    y_full: np.ndarray | None
    steps: np.ndarray
    nfev: np.ndarray
    status: str
    reason: str
    setup_seconds: float
    seconds: float
    info: dict
    njev: np.ndarray | None = None
