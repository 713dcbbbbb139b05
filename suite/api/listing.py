"""``gnibench.problems()``, ``gnibench.methods()``, ``gnibench.metrics()``: the registries as
DataFrames, with the content of ``gnibench list`` (:mod:`gnibench.suite.cli.listing`)."""
from __future__ import annotations


def _frame(what: str):
    import pandas as pd
    from gnibench.suite.cell.user.loader import discover
    from gnibench.suite.cli.listing import _params, listing

    discover()                      # GNIBENCH_LOAD and entry points, as `gnibench list`
    rows = []
    for r in listing(what):
        row = {k: v for k, v in r.items() if k != "properties"}
        row.update(r.get("properties", {}))            # methods: implicit, explicit, symplectic, ...
        row["options"] = _params(r["params"])          # as the text listing prints them
        rows.append(row)
    return pd.DataFrame(rows)


def problems():
    """The problems: one row per problem (``id``, ``title``, ``reference``, ``state``,
    ``integrals``, ``partition``, ``exact_solution``, ``period``, ``params``, ``options``,
    ``notes``, ...), as ``gnibench list problems``."""
    return _frame("problems")


def methods():
    """The methods and modifiers: one row each (``id``, ``kind`` — ``compiled``, ``external``,
    ``python`` or ``modifier`` —, ``family``, ``order``, ``reference``, ``doc``, the properties
    ``implicit``, ``explicit``, ``symplectic``, ``symmetric``, ``needs_partition``, ...,
    ``params``, ``options``), as ``gnibench list methods``."""
    return _frame("methods")


def metrics():
    """The metrics: one row each (``id``, ``title``, ``reference``, ``doc``, ``scope``,
    ``needs``, ``default``, ``params``, ``columns``, ``scalars``, ``options``), as
    ``gnibench list metrics``."""
    return _frame("metrics")
