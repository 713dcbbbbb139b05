"""User definitions: problems and methods brought without editing the package.

A TOML file of ``[[problem]]`` and ``[[method]]`` entries (:mod:`.problems`, :mod:`.methods`),
loaded by ``--load FILE``, ``GNIBENCH_LOAD``, an experiment's ``load = [...]``, ``gnibench.load``
or the entry points ``gnibench.problems`` / ``gnibench.methods`` (:mod:`.loader`). Expressions are
read from a safe subset (:mod:`.expressions`); Python integrators run through
:mod:`.python_methods`. The documentation's reference page "User definitions" is the public contract.
"""
from gnibench.suite.cell.user.loader import discover, load, loaded, unload

__all__ = ["discover", "load", "loaded", "unload"]
