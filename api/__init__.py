"""The Python API: the command line's ``solve``, ``run``, ``verify``, ``reproduce``, ``report``
and ``list`` as functions that return pandas DataFrames (README, "Python API").

``gnibench`` re-exports every name here on first use. Errors raise
:class:`~gnibench.suite.foundation.errors.UserError` with the line the command line prints.
"""
from gnibench.api.listing import methods, metrics, problems
from gnibench.api.running import RunResult, report, reproduce, run, verify
from gnibench.api.solving import Trajectory, solve
from gnibench.suite.foundation.errors import UserError

__all__ = ["RunResult", "Trajectory", "UserError", "methods", "metrics", "problems", "report",
           "reproduce", "run", "solve", "verify"]
