"""``gnibench list``: the records of :func:`gnibench.suite.api.listing.listing` as aligned text."""
from __future__ import annotations

from gnibench.suite.api.listing import options_text as _params


def as_table(what: str, rows: list[dict]) -> str:
    out = []
    if what == "metrics":
        for r in rows:
            flags = ["default"] if r["default"] else []
            flags += ["across the cells of a family"] if r["scope"] == "family" else []
            flags += [f"needs {n}" for n in r["needs"]]
            out.append(f"{r['id']}  {r['title']}  [{', '.join(flags)}]  {r['reference']}")
            out.append(f"    {r['doc']}")
            if r["params"]:
                out.append(f"    options: {_params(r['params'])}")
            for kind in ("columns", "scalars"):
                if r[kind]:
                    where = "per sample" if kind == "columns" else "per cell"
                    out.append(f"    {where}: " + "; ".join(f"{k} = {v}" for k, v in r[kind].items()))
        return "\n".join(out)
    if what == "problems":
        for r in rows:
            out.append(f"{r['id']}  {r['title']}  {r['reference']}")
            out.append(f"    state: {', '.join(r['state'])}   integrals: {', '.join(r['integrals'])}"
                       f"   partition: {r['partition'] and ' | '.join(','.join(b) for b in r['partition'])}"
                       f"   exact solution: {'yes' if r['exact_solution'] else 'no'}"
                       f"   period: {'yes' if r['period'] else 'no'}")
            out.append(f"    options: {_params(r['params'])}")
            if r["notes"]:
                out.append(f"    notes: {r['notes']}")
        return "\n".join(out)
    for r in rows:
        if r.get("kind") == "modifier":
            out.append(f"+{r['id']}  (modifier)  {r['reference']}  {r['doc']}")
        else:
            props = [k for k, v in r["properties"].items() if v is True]
            ex = r["properties"]["explicit"]
            if isinstance(ex, str):
                props.append(f"explicit {ex}")
            order = r["order"] or "not declared"     # a Python method may declare none
            out.append(f"{r['id']}  order {order}  {r['family']}  [{', '.join(props)}]  "
                       f"{r['reference']}  {r['doc']}")
        out.append(f"    options: {_params(r['params'])}")
    return "\n".join(out)
