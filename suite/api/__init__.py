"""The Python API: the command line's ``solve``, ``run``, ``verify``, ``reproduce``, ``report``
and ``list`` as functions that return pandas DataFrames (README, "Python API").

``gnibench`` re-exports every name here on first use. ``load(path)`` defines the problems and
methods of a TOML file of user definitions (:mod:`gnibench.suite.cell.user`); ``GNIBENCH_LOAD``
and the installed entry points are loaded by the first call of a function here, as by the
command line. Errors raise
:class:`~gnibench.suite.foundation.errors.UserError` with the line the command line prints.
"""
from gnibench.suite.api.listing import methods, metrics, problems
from gnibench.suite.api.running import RunResult, report, reproduce, run, verify
from gnibench.suite.api.solving import Trajectory, solve
from gnibench.suite.cell.user.loader import load
from gnibench.suite.foundation.errors import UserError

__all__ = ["RunResult", "Trajectory", "UserError", "load", "methods", "metrics", "problems",
           "report", "reproduce", "run", "solve", "verify"]
