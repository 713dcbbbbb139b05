"""The families of a report and their names: a curve, a league-table row and an order fit hold
the cells of one setup only.

The families are those of the ``order`` metric (:func:`gnibench.suite.metrics.families.setups`:
problem and its options, method options but the swept ones, horizon, output grid, reference), so
the report and the metric agree. A family is named by its label (the cells' column ``family``,
e.g. ``dop853``) and, where several families of the same label meet in one page section or one
figure, by what distinguishes them: ``dop853 (T = 62.8319)``, ``dop853 (atol=1e-10)``,
``dop853 (atol default)``, ``rk4 (every 40)``.

(choice) An experiment whose cells cannot be grouped into one family per method is drawn, not
refused: mixing horizons or tolerances in one experiment is a fair question (one period and ten),
and each setup gets its own curve, row and fit. The work-precision diagrams and league tables of a
page section are drawn per **context**: the cells of one problem, horizon and reference, since
costs and errors over another horizon or against another reference are not comparable; families
of other output grids or method options share a context.
"""
from __future__ import annotations

#: the options named first when they tell families apart (a step size or tolerance)
TOLERANCES = ("h", "rtol", "atol", "tol", "epsilon")


def add_setups(cells):
    """The cells with columns ``setup`` (the family: its smallest cell id), ``context`` (problem,
    final time and reference, as text) and ``swept_text`` (the swept options and their values,
    ``rtol=1e-08``, ``rtol=atol=1e-08``)."""
    from gnibench.suite.metrics.families import final_time, setup_key, setups

    out = cells.copy()
    if "swept" not in out:                    # tables written before the column: its sweep
        out["swept"] = out["sweep"].fillna("")
        cells = out
    out["setup"] = setups(cells) if len(cells) else []
    rows = cells.to_dict("records")
    out["context"] = ["\x1f".join((str(r["problem"]), final_time(r), str(r.get("reference") or "")))
                      for r in rows]
    out["swept_text"] = [swept_text(r) for r in rows]
    out["_key"] = [setup_key(r) for r in rows]
    return out


def swept_text(row) -> str:
    """The swept options of a cell and their values: ``h=0.01``, ``rtol=atol=1e-08`` (one value),
    ``rtol=1e-08, atol=1e-10``; "" when nothing is swept."""
    names = [n for n in str(row.get("swept") or "").split("/") if n]
    from gnibench.suite.metrics.families import method_options

    given = method_options(row["method"])
    pairs = [(n, given[n]) for n in names if n in given]
    if not pairs:
        return ""
    if len({v for _, v in pairs}) == 1:
        return "=".join(n for n, _ in pairs) + "=" + pairs[0][1]
    return ", ".join(f"{n}={v}" for n, v in pairs)


def _part_texts(key: tuple) -> dict[str, str]:
    problem, method, horizon, every, dt_out, section, reference = key
    return {"problem": problem, "method": method, "horizon": f"T = {float(horizon):.6g}",
            "every": f"every {every}" if every else "", "dt_out": f"dt_out {dt_out}" if dt_out
            else "", "section": f"{section} crossings" if section else "",
            "reference": f"against {reference or 'the exact solution'}"}


def _method_words(methods: list[str], swept: list[str]) -> list[dict[str, str]]:
    """For each method spec (without its swept options ``swept``, "/"-joined), the words of its
    options that differ among them, by ``option <name>``: ``name=value``, else ``name swept``
    or ``name default``."""
    from gnibench.suite.metrics.families import method_options

    opts = [method_options(m) for m in methods]
    names = list(dict.fromkeys(k for o in opts for k in o))
    differ = [k for k in names if len({o.get(k) for o in opts}) > 1]
    out = []
    for o, sw in zip(opts, swept):
        words = {}
        for k in differ:
            if k.startswith("+"):
                words[f"option {k}"] = k if k in o else f"no {k}"
            elif k in o:
                words[f"option {k}"] = f"{k}={o[k]}"
            else:
                words[f"option {k}"] = f"{k} swept" if k in str(sw).split("/") else \
                    f"{k} default"
        out.append(words)
    return out


def family_names(cells) -> dict[int, str]:
    """The name of each family (by setup id) of the cells given (:func:`add_setups` columns):
    its label and, where several families of these cells share it, the fewest parts of its
    setup that tell them apart, taken in the order problem, horizon, reference, the method's
    step-size and tolerance options, its other options (as the spec orders them), output grid
    (see the module docstring)."""
    first = cells.drop_duplicates("setup")
    setups = [int(s) for s in first["setup"]]
    labels = dict(zip(setups, first["family"].astype(str)))
    keys = dict(zip(setups, first["_key"]))
    swept = dict(zip(setups, first["swept"].astype(str)))
    names = {}
    for label in dict.fromkeys(labels.values()):
        mine = [s for s in setups if labels[s] == label]
        words: dict[int, list[str]] = {s: [] for s in mine}
        if len(mine) > 1:
            texts = {s: _part_texts(keys[s]) for s in mine}
            methods = dict(zip(mine, _method_words([keys[s][1] for s in mine],
                                                   [swept[s] for s in mine])))
            parts = [texts[s] | methods[s] for s in mine]
            given = list(dict.fromkeys(k for p in parts for k in p if k.startswith("option ")))
            tolerances = [f"option {k}" for k in TOLERANCES if f"option {k}" in given]
            order = ["problem", "horizon", "reference"] + tolerances + \
                [k for k in given if k not in tolerances] + ["every", "dt_out", "section"]
            buckets = [mine]
            for part in order:
                split = []
                for bucket in buckets:
                    values = {s: (texts[s] | methods[s]).get(part, "") for s in bucket}
                    if len(bucket) > 1 and len(set(values.values())) > 1:
                        for s in bucket:
                            if values[s]:
                                words[s].append(values[s])
                        split += [[s for s in bucket if values[s] == v]
                                  for v in dict.fromkeys(values.values())]
                    else:
                        split.append(bucket)
                buckets = split
        for s in mine:
            names[s] = f"{label} ({'; '.join(words[s])})" if words[s] else label
    return names


def positions(values) -> dict:
    """The rows of each value of ``values`` (a column without missing values): {value: row
    positions, ascending}, the values in order of their first row. One pass over the table: a
    report selects the cells of each family or context from it instead of comparing the whole
    column once per family (a cost quadratic in the number of families)."""
    import numpy as np
    import pandas as pd

    codes, uniques = pd.factorize(np.asarray(values), sort=False)
    order = np.argsort(codes, kind="stable")
    ends = np.cumsum(np.bincount(codes, minlength=len(uniques)))
    return dict(zip(uniques.tolist(), np.split(order, ends[:-1])))


def context_names(keys: list[str]) -> list[str]:
    """The name of each context (:func:`add_setups` column ``context``) of a page section: what
    sets it apart from the others ("" when there is one): its horizon, its reference, its
    problem."""
    if len(keys) == 1:
        return [""]
    parts = [c.split("\x1f") for c in keys]
    differ = [len({p[i] for p in parts}) > 1 for i in range(3)]   # problem, horizon, reference
    out = []
    for problem, horizon, reference in parts:
        words = []
        if differ[0]:
            words.append(problem)
        if differ[1]:
            words.append(f"T = {float(horizon):.6g}")
        if differ[2]:
            words.append(f"against {reference or 'the exact solution'}")
        out.append("; ".join(words))
    return out


def context_rows(cells) -> list[tuple[str, str, object]]:
    """The contexts of a page section's cells, in order of their first cell: (key, name, row
    positions), named by :func:`context_names`."""
    rows = positions(cells["context"])
    return list(zip(rows, context_names(list(rows)), rows.values()))


def contexts(cells) -> list[tuple[str, object]]:
    """The contexts of a page section's cells, in order of their first cell: (name, cells). The
    name says what sets the context apart from the others of the section ("" when there is one):
    its horizon, its reference, its problem."""
    return [(name, cells.iloc[rows]) for _, name, rows in context_rows(cells)]


def point_label(name: str, swept: str) -> str:
    """A legend label of one cell: its family's name and its swept value."""
    return f"{name} {swept}".strip()

