"""gnibench: benchmark and verification suite for integrators of ODEs with first integrals.

The Python API (:mod:`gnibench.suite.api`)::

    import gnibench
    traj = gnibench.solve("kepler-2d", "dopri5:rtol=1e-10,atol=1e-10", t_end=62.83)
    traj.samples            # a pandas DataFrame: the columns of `gnibench solve`
    res = gnibench.run("quick")                  # .samples, .cells, .timings DataFrames
    gnibench.list_methods()                      # the registry, as `gnibench list methods`
    gnibench.plot.work_precision(res)            # the report's figures, as matplotlib figures

Its names are imported on first use, so ``import gnibench`` stays cheap (no numba, sympy or
pandas until a function is called). ``gnibench.problems``, ``gnibench.methods``, ... are the
package's subpackages (the registries), as for any package.
"""
from gnibench.suite.foundation.version import VERSION

__version__ = VERSION

__all__ = ["RunResult", "Trajectory", "UserError", "list_methods", "list_metrics",
           "list_problems", "load", "report", "reproduce", "run", "solve", "verify"]
_SUBPACKAGES = ("methods", "problems", "reports", "suite")
#: modules of the API under their own name: ``gnibench.plot.work_precision(result)``
_MODULES = {"plot": "gnibench.plot"}
#: names of earlier releases that Python can still point to (``gnibench.methods()`` and
#: ``gnibench.problems()`` cannot: those names are the subpackages, and calling a module raises
#: Python's own TypeError)
_RENAMED = {"metrics": "list_metrics"}


def __getattr__(name: str):
    if name in __all__:
        from gnibench.suite import api

        return getattr(api, name)
    if name in _SUBPACKAGES:
        import importlib

        return importlib.import_module(f"{__name__}.{name}")
    if name in _MODULES:
        import importlib

        return importlib.import_module(_MODULES[name])
    if name in _RENAMED:
        raise AttributeError(f"module 'gnibench' has no attribute {name!r}: the listing is "
                             f"gnibench.{_RENAMED[name]}() (renamed, see the changelog)")
    raise AttributeError(f"module 'gnibench' has no attribute {name!r}")


def __dir__():
    return sorted(list(globals()) + __all__ + list(_MODULES))
