"""gnibench: benchmark and verification suite for integrators of ODEs with first integrals.

The Python API (README, "Python API"; :mod:`gnibench.suite.api`)::

    import gnibench
    traj = gnibench.solve("kepler-2d", "dopri5:rtol=1e-10,atol=1e-10", t_end=62.83)
    traj.samples            # a pandas DataFrame: the columns of `gnibench solve`
    res = gnibench.run("quick")                  # .samples, .cells, .timings DataFrames

Its names are imported on first use, so ``import gnibench`` stays cheap (no numba, sympy or
pandas until a function is called).

``gnibench.problems`` and ``gnibench.methods`` are both the registries' subpackages and the API's
listings: calling the subpackage, ``gnibench.methods()``, returns the DataFrame of
:func:`gnibench.suite.api.listing.methods` (a module may be given a callable class,
``module.__class__ = ...``, Python >= 3.5); ``from gnibench.methods import METHODS`` and
``import gnibench.methods.external`` work as for any package.
"""
import sys
import types

from gnibench.suite.foundation.version import VERSION

__version__ = VERSION

__all__ = ["RunResult", "Trajectory", "UserError", "load", "methods", "metrics", "problems",
           "report", "reproduce", "run", "solve", "verify"]
_LISTINGS = ("methods", "problems")      # subpackages that are also listings of the API


class _Listing(types.ModuleType):
    """A registry subpackage that, called, lists its registry as a DataFrame."""

    def __call__(self):
        from gnibench.suite.api import listing

        return getattr(listing, self.__name__.rpartition(".")[2])()


class _Package(types.ModuleType):
    """The package ``gnibench``: its subpackages ``methods`` and ``problems`` become callable
    when the import system sets them as its attributes."""

    def __setattr__(self, name, value):
        if name in _LISTINGS and type(value) is types.ModuleType:
            value.__class__ = _Listing
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package


def __getattr__(name: str):
    if name in _LISTINGS:
        import importlib

        return importlib.import_module(f"{__name__}.{name}")
    if name in __all__:
        from gnibench.suite import api

        return getattr(api, name)
    raise AttributeError(f"module 'gnibench' has no attribute {name!r}")


def __dir__():
    return sorted(list(globals()) + __all__)
