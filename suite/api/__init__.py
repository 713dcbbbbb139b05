"""The Python API: the library the command line is a shell on.

``solve``, ``run``, ``verify``, ``reproduce``, ``report``, ``load`` and the listings
``list_problems``, ``list_methods``, ``list_metrics`` return pandas DataFrames (or paths, or
:class:`Trajectory` / :class:`RunResult` records); ``gnibench`` re-exports every name here on
first use. Every function checks its arguments against one schema before any work
(:mod:`gnibench.suite.api.arguments`); bad input raises :class:`UserError` with one line (the
line the command line prints). ``GNIBENCH_LOAD`` and the installed entry points are loaded by the
first call that needs the registries, as by the command line.
"""
from gnibench.suite.api.listing import list_methods, list_metrics, list_problems
from gnibench.suite.api.loading import load
from gnibench.suite.api.reporting import report
from gnibench.suite.api.reproducing import reproduce
from gnibench.suite.api.running import RunResult, run
from gnibench.suite.api.solving import Trajectory, solve
from gnibench.suite.api.verifying import verify
from gnibench.suite.foundation.errors import UserError

__all__ = ["RunResult", "Trajectory", "UserError", "list_methods", "list_metrics",
           "list_problems", "load", "report", "reproduce", "run", "solve", "verify"]
