"""``gnibench.list_problems()``, ``gnibench.list_methods()``, ``gnibench.list_metrics()``: the
registries as DataFrames with fixed columns; ``gnibench list`` prints the same records
(:func:`listing`) as text or JSON.

The columns are part of the public API (:data:`PROBLEM_COLUMNS`, :data:`METHOD_COLUMNS`,
:data:`METRIC_COLUMNS`): the same, in the same order, whatever the registries hold (user
definitions included); a value a record does not have is None.
"""
from __future__ import annotations

from gnibench.suite.api.arguments import api_function

#: the columns of :func:`list_problems`
PROBLEM_COLUMNS = ("id", "title", "reference", "state", "integrals", "partition", "separable",
                   "exact_solution", "period", "params", "options", "notes")
#: the columns of :func:`list_methods`
METHOD_COLUMNS = ("id", "kind", "family", "order", "reference", "doc", "implicit", "explicit",
                  "symplectic", "symmetric", "needs_partition", "adaptive", "engine", "acts_on",
                  "params", "options")
#: the columns of :func:`list_metrics`
METRIC_COLUMNS = ("id", "title", "reference", "doc", "scope", "needs", "default", "params",
                  "columns", "scalars", "options")
COLUMNS = {"problems": PROBLEM_COLUMNS, "methods": METHOD_COLUMNS, "metrics": METRIC_COLUMNS}


def listing(what: str) -> list[dict]:
    """The records of a registry as ``gnibench list`` prints them (``what``: ``problems``,
    ``methods`` (with the modifiers) or ``metrics``), user definitions included."""
    from gnibench.suite.cell.user.loader import discover

    discover()                      # GNIBENCH_LOAD and entry points
    if what == "problems":
        from gnibench.problems import REGISTRY

        return [p.describe() for p in REGISTRY.values()]
    if what == "metrics":
        from gnibench.suite.metrics import METRICS

        return [m.describe() for m in METRICS.values()]
    from gnibench.methods import METHODS, MODIFIERS

    return [m.describe() for m in METHODS.values()] + [m.describe() for m in MODIFIERS.values()]


def _default(p: dict) -> str:
    d = p["default"]
    if d is None:
        return "-"
    if isinstance(d, tuple):
        return "/".join(f"{x:g}" if isinstance(x, (int, float)) else str(x) for x in d)
    return str(d)


def options_text(params: list[dict]) -> str:
    """A record's options on one line: ``name=default (range); ...``."""
    return "; ".join(f"{p['name']}={_default(p)} ({p['range']})" for p in params)


def _row(record: dict) -> dict:
    row = {k: v for k, v in record.items() if k != "properties"}
    props = record.get("properties", {})
    row.update(props)                  # methods: implicit, explicit, symplectic, adaptive, ...
    if row.get("kind") not in (None, "modifier"):
        row.setdefault("adaptive", _adaptive_default(record))
    row["options"] = options_text(record["params"])
    return row


def _adaptive_default(record: dict) -> bool:
    """A compiled method chooses its steps when its option ``adaptive`` is on by default."""
    return any(p["name"] == "adaptive" and p["default"] is True for p in record["params"])


def _frame(what: str):
    import pandas as pd

    columns = COLUMNS[what]
    rows = [_row(r) for r in listing(what)]
    df = pd.DataFrame([{c: r.get(c) for c in columns} for r in rows], columns=list(columns))
    for col, dtype in _DTYPES.get(what, {}).items():
        df[col] = df[col].astype(dtype)
    return df


#: columns with a missing value for some rows (modifiers, undeclared orders), as nullable dtypes
_DTYPES = {"methods": {"order": "Int64", "implicit": "boolean", "symplectic": "boolean",
                       "symmetric": "boolean", "needs_partition": "boolean",
                       "adaptive": "boolean"}}


@api_function
def list_problems():
    """The problems of the registry (shipped and user-defined), as ``gnibench list problems``.

    Returns
    -------
    pandas.DataFrame
        One row per problem, with the columns of :data:`PROBLEM_COLUMNS`: ``id``, ``title``,
        ``reference``, ``state`` (the state variables), ``integrals`` (the first integrals'
        names), ``partition`` (the blocks (q, p) of a partitioned problem, or None),
        ``separable``, ``exact_solution``, ``period`` (whether it has them), ``params`` (the
        options as records: name, default, kind, range, doc), ``options`` (the same on one
        line) and ``notes``.

    Examples
    --------
    >>> import gnibench
    >>> problems = gnibench.list_problems().set_index("id")
    >>> problems.loc["kepler-2d", ["state", "integrals"]].tolist()
    [['p1', 'p2', 'q1', 'q2'], ['H', 'L', 'A1', 'A2']]
    """
    return _frame("problems")


@api_function
def list_methods():
    """The methods and modifiers of the registry, as ``gnibench list methods``.

    Returns
    -------
    pandas.DataFrame
        One row per method or modifier, with the columns of :data:`METHOD_COLUMNS`: ``id``,
        ``kind`` (``compiled``: a gnibench kernel; ``external``: heyoka, rebound or scipy;
        ``python``: a user's Python integrator; ``modifier``), ``family``, ``order`` (Int64;
        missing when not declared), ``reference``, ``doc``, the properties ``implicit``,
        ``explicit`` (True, False, or the condition, e.g. ``when separable``), ``symplectic``,
        ``symmetric``, ``needs_partition``, ``adaptive`` (chooses its own steps by default;
        nullable booleans, missing for a modifier), ``engine`` (of an external method),
        ``acts_on`` (of a modifier: ``field`` or ``step``), ``params`` and ``options``. A value
        that does not apply is missing.

    Examples
    --------
    >>> import gnibench
    >>> methods = gnibench.list_methods().set_index("id")
    >>> rk4 = methods.loc["rk4"]
    >>> rk4["kind"], int(rk4["order"]), bool(rk4["symplectic"])
    ('compiled', 4, False)
    >>> methods.loc["observer", "kind"]
    'modifier'
    """
    return _frame("methods")


@api_function
def list_metrics():
    """The metrics of the registry, as ``gnibench list metrics``.

    Returns
    -------
    pandas.DataFrame
        One row per metric, with the columns of :data:`METRIC_COLUMNS`: ``id``, ``title``,
        ``reference``, ``doc``, ``scope`` (``cell`` or ``family``: across the cells of a step
        sweep), ``needs`` (what the cell must provide), ``default`` (computed for every cell),
        ``params``, ``columns`` (per-sample columns and their meaning), ``scalars`` (per-cell
        values) and ``options``.

    Examples
    --------
    >>> import gnibench
    >>> metrics = gnibench.list_metrics().set_index("id")
    >>> bool(metrics.loc["global_error", "default"])
    True
    """
    return _frame("metrics")
