"""One page per problem, method, modifier and metric, generated from the registry records.

Each page shows what ``gnibench list`` prints of the record (its ``describe()``), laid out for
reading: the seed reference, order and properties, the options with defaults and allowed ranges,
and for a problem the equations and first integrals as LaTeX, printed by sympy from the
problem's own model (the single source of its compiled code). User definitions (records with an
``origin``) are not documented here: only what gnibench ships.
"""
from __future__ import annotations

from pathlib import Path

from .common import Tree, cell, code, options_table, table

KINDS = ("problems", "methods", "modifiers", "metrics")


def records(kind: str) -> list:
    """The shipped records of one registry, in registry order."""
    if kind == "problems":
        from gnibench.problems import REGISTRY as reg
    elif kind == "methods":
        from gnibench.methods import METHODS as reg
    elif kind == "modifiers":
        from gnibench.methods import MODIFIERS as reg
    else:
        from gnibench.suite.metrics import METRICS as reg
    return [r for r in reg.values() if getattr(r, "origin", None) is None]


def ids(kind: str) -> list[str]:
    return [r.id for r in records(kind)]


# --- problems ---------------------------------------------------------------------------------

def _symbols(problem):
    import sympy as sp
    from types import SimpleNamespace

    names = {s: sp.Symbol(_tex_name(s), real=True) for s in problem.state}
    params = {p: sp.Symbol(_tex_name(p), real=True) for p in problem.model_params}
    return names, params, SimpleNamespace(**names, **params)


def _tex_name(name: str) -> str:
    """A state or parameter name as a sympy symbol name that prints well (q1 -> q_{1})."""
    greek = {"mu", "omega", "Omega", "lam", "eps", "alpha", "beta", "theta", "lambda"}
    head = name.rstrip("0123456789")
    tail = name[len(head):]
    if head == "lam":
        head = "lambda"
    if head == "eps":
        head = "epsilon"
    if "_" in head and not tail:
        a, _, b = head.partition("_")
        return f"{a}_{{{b.replace('_', ' ')}}}"
    return f"{head}_{{{tail}}}" if tail else (head if head in greek or len(head) == 1 else head)


def _dot(tex: str) -> str:
    """The time derivative of a symbol printed by sympy: q_{1} -> \\dot{q}_{1}."""
    base, sep, sub = tex.partition("_")
    return rf"\dot{{{base}}}" + (sep + sub if sep else "")


def equations(problem) -> str:
    """The problem's vector field and first integrals as a LaTeX block, from its sympy model
    ("" when the model cannot be printed)."""
    import sympy as sp

    try:
        names, _, ns = _symbols(problem)
        model = problem.model(ns)
        lines = []
        if model.hamiltonian is not None:
            lines.append(rf"H = {sp.latex(model.hamiltonian)}")
            pn, qn = problem.canonical
            pairs = ", ".join(f"({sp.latex(names[q])}, {sp.latex(names[p])})" for p, q in zip(pn, qn))
            field = [_dot(sp.latex(names[q])) + rf" = \partial H/\partial {sp.latex(names[p])}"
                     for p, q in zip(pn, qn)]
            field += [_dot(sp.latex(names[p])) + rf" = -\partial H/\partial {sp.latex(names[q])}"
                      for p, q in zip(pn, qn)]
            block = ["$$", r"\begin{aligned}", rf"& {lines[0]} \\",
                     r"& " + r", \quad ".join(field[:3]) + (r", \ \ldots" if len(field) > 3 else ""),
                     r"\end{aligned}", "$$"]
            text = "\n".join(block) + f"\n\nCanonical pairs (q, p): ${pairs}$ ([HLW] (1.10)).\n"
        else:
            rows = [_dot(sp.latex(names[s])) + rf" &= {sp.latex(f)}"
                    for s, f in zip(problem.state, model.rhs)]
            text = "$$\n\\begin{aligned}\n" + " \\\\\n".join(rows) + "\n\\end{aligned}\n$$\n"
        ints = [rf"{_int_name(k)} &= {sp.latex(v)}" for k, v in model.integrals.items()]
        if ints:
            text += ("\nFirst integrals:\n\n$$\n\\begin{aligned}\n" + " \\\\\n".join(ints)
                     + "\n\\end{aligned}\n$$\n")
        partial = getattr(model, "partial_integrals", {}) or {}
        if partial:
            text += "\nPartial first integrals ([B] (2.12)): " + ", ".join(
                f"`{k}`" for k in partial) + ".\n"
        return text
    except Exception as e:          # a model that does not print is documented without formulas
        return f"(The model could not be printed: {type(e).__name__}.)\n"


def _int_name(name: str) -> str:
    if name == "c_sq":
        return r"\lVert c \rVert^2"
    return r"\mathrm{" + name.replace("_", r"\_") + "}"


def problem_page(p) -> str:
    d = p.describe()
    out = [f"# `{p.id}`: {p.title}\n", f"Source: {p.reference}\n"]
    facts = [["state", code(" ".join(d["state"]))],
             ["first integrals", cell(", ".join(d["integrals"]) or "none")],
             ["partition", cell(" | ".join(",".join(b) for b in d["partition"]) if d["partition"]
                                else "none")],
             ["separable", cell(bool(d.get("separable")))],
             ["exact solution", cell(bool(d["exact_solution"]))],
             ["period", cell(bool(d["period"]))]]
    for s in p.sections:
        facts.append(["Poincaré section", cell(f"{s.name}, coordinates ({', '.join(s.coords)})"
                                               + (f", charts 1..{s.charts}" if s.charts else "")
                                               + (f"; {s.reference}" if s.reference else ""))])
    if p.transform is not None:
        facts.append(["transform", cell(f"option {p.transform.option}=true: {p.transform.doc}")])
    if p.boundary is not None:
        facts.append(["identification map", cell(p.boundary.reference or "yes")])
    out.append(table(["property", "value"], facts))
    out.append("## Equations\n")
    out.append(equations(p))
    out.append("## Options\n")
    out.append("Initial values are the options `<state>0` (`" + p.id + ":" + d["state"][0]
               + "0=...`); the others are the problem's parameters.\n")
    out.append(options_table(d["params"]))
    if d.get("notes"):
        out.append("## Choices and notes\n")
        out.append(" ".join(d["notes"].split()) + "\n")
    out.append(_used_by("problems", p.id))
    return "\n".join(out)


# --- methods and modifiers --------------------------------------------------------------------

def _properties(d: dict) -> str:
    props = d.get("properties", {})
    shown = []
    for k in ("explicit", "implicit", "symplectic", "symmetric", "needs_partition"):
        v = props.get(k)
        if v is True:
            shown.append(k.replace("_", " "))
        elif isinstance(v, str) and v:
            shown.append(f"explicit {v}")
    return ", ".join(shown) or "–"


def tableau(m) -> str:
    """The Butcher tableau of a Runge–Kutta method with at most 7 stages ("" otherwise)."""
    t = getattr(m, "data", None)
    a, b, c = (getattr(t, k, None) for k in ("a", "b", "c"))
    if a is None or b is None or c is None or len(b) > 7:
        return ""
    try:
        import sympy as sp

        def tex(x):
            return sp.latex(sp.nsimplify(x) if not isinstance(x, (int, sp.Basic)) else x)

        s = len(b)
        rows = []
        for i in range(s):
            row = list(a[i]) + [0] * (s - len(a[i]))
            rows.append(tex(c[i]) + " & " + " & ".join(tex(x) for x in row))
        rows.append(r"\hline" + " & " + " & ".join(tex(x) for x in b))
        return ("$$\n\\begin{array}{c|" + "c" * s + "}\n" + " \\\\\n".join(rows)
                + "\n\\end{array}\n$$\n")
    except Exception:
        return ""


def short(doc: str, limit: int = 60) -> str:
    """A record's one-line description cut to a title: its first clause when it is long."""
    doc = " ".join(doc.split())
    if len(doc) <= limit:
        return doc
    import re

    head = re.split(r"[:;(]| - ", doc, maxsplit=1)[0].strip().rstrip(",")
    return head if 0 < len(head) <= limit else doc[:limit].rsplit(" ", 1)[0] + " …"


def method_page(m) -> str:
    d = m.describe()
    out = [f"# `{m.id}`: {short(d['doc'])}\n", f"{d['doc']}\n", f"Source: {d['reference']}\n"]
    facts = [["kind", cell(d.get("kind", "compiled"))], ["family", cell(d.get("family", ""))],
             ["order", cell(d.get("order") or "not declared")],
             ["properties", cell(_properties(d))]]
    aliases = getattr(m, "aliases", ())
    if aliases:
        facts.append(["aliases", cell(", ".join(aliases))])
    refused = getattr(m, "field_modifiers_refused", "")
    if refused:
        facts.append(["modifiers", cell(f"+observer and +penalty refused: {refused}")])
    if getattr(m, "summation", None):
        facts.append(["summation default", code(m.summation)])
    out.append(table(["property", "value"], facts))
    tab = tableau(m)
    if tab:
        out.append("## Butcher tableau\n")
        out.append(tab)
    out.append("## Options\n")
    out.append(options_table(d["params"]))
    out.append("Spec string: `" + m.id + "[:option=value,...]`, e.g. in "
               "`gnibench solve PROBLEM " + m.id + ":" + (d["params"][0]["name"] + "=..."
                                                          if d["params"] else "") + "`; "
               "see {doc}`/reference/specs`.\n")
    out.append(_used_by("methods", m.id))
    return "\n".join(out)


def modifier_page(m) -> str:
    d = m.describe()
    acts = {"field": "adds a term to the vector field F, which any base method then integrates",
            "step": "maps the result of each step of the base method"}.get(d.get("acts_on"), "")
    out = [f"# `+{m.id}`: {short(d['doc'])}\n", f"{d['doc']}\n", f"Source: {d['reference']}\n",
           f"A modifier: it {acts}. Write it after a base method: "
           f"`rk4:h=0.01+{m.id}[:option=value,...]`.\n"]
    if getattr(m, "needs_independent", False):
        out.append("The observed integrals must be functionally independent on the level set "
                   "([B] §2: rank D_H = q, else D_H D_Hᵀ is singular): observe a subset with "
                   "`on=`.\n")
    out.append("## Options\n")
    out.append(options_table(d["params"]))
    out.append("See {doc}`/how-to/modifiers` for what each does and when to use it.\n")
    out.append(_used_by("methods", m.id))
    return "\n".join(out)


# --- metrics ----------------------------------------------------------------------------------

def metric_page(m) -> str:
    d = m.describe()
    flags = ["computed by default"] if d.get("default") else ["chosen with --metrics or metrics = [...]"]
    if d.get("scope") == "family":
        flags.append("computed across the cells of a family (experiments only)")
    flags += [f"needs {n}" for n in d.get("needs", [])]
    out = [f"# `{m.id}`: {d['title']}\n", f"Source: {d['reference']}\n", d["doc"] + "\n",
           "- " + "\n- ".join(flags) + "\n"]
    out.append("## Options\n")
    out.append(options_table(d.get("params", [])))
    for key, title in (("columns", "Per-sample columns (samples table)"),
                       ("scalars", "Per-cell values (cells table, meta.metrics)")):
        if d.get(key):
            out.append(f"## {title}\n")
            out.append(table(["column", "meaning"],
                             [[code(k), cell(v)] for k, v in d[key].items()]))
    out.append("How it is computed, with the formulas: {doc}`/explanation/metrics`.\n")
    return "\n".join(out)


# --- the experiments that use an id -----------------------------------------------------------

_USES: dict | None = None


def _uses() -> dict:
    """{(kind, id): [experiment names]} of the shipped experiments (their TOML text, read once)."""
    global _USES
    if _USES is None:
        import re

        from gnibench.suite.runs.experiment import shipped

        _USES = {}
        for name, text in sorted(shipped().items()):
            for word in set(re.findall(r"[\"'+]([A-Za-z][\w.-]*)", text)):
                _USES.setdefault(word, []).append(name)
    return _USES


def _used_by(kind: str, rid: str) -> str:
    names = _uses().get(rid, [])
    if not names:
        return ""
    links = ", ".join(f"`{n}`" for n in names)
    return f"## Shipped experiments that use it\n\n{links}\n"


# --- the pages --------------------------------------------------------------------------------

PAGE = {"problems": problem_page, "methods": method_page, "modifiers": modifier_page,
        "metrics": metric_page}
TITLE = {"problems": "Problems", "methods": "Methods", "modifiers": "Modifiers",
         "metrics": "Metrics"}
INTRO = {
    "problems": "The shipped problems: id, source in the seeds, state, first integrals. Each id "
                "is a PROBLEM spec string (`kepler-2d:e=0.6`); a page per problem below.",
    "methods": "The shipped base integrators, compiled (numba kernels), external engines "
               "(heyoka, rebound, scipy's `solve_ivp`) and their orders and properties.",
    "modifiers": "Modifiers wrap any base method: `METHOD+modifier[:options]`.",
    "metrics": "Metrics are functions of a trajectory: per-sample columns and per-cell values.",
}


def _summary(kind: str, r) -> list[str]:
    d = r.describe()
    link = f"[`{r.id}`]({r.id}.md)"
    if kind == "problems":
        return [link, cell(d["title"]), cell(d["reference"]), code(" ".join(d["state"])),
                cell(", ".join(d["integrals"]))]
    if kind == "methods":
        return [link, cell(d["doc"]), cell(d.get("order") or "–"), cell(d.get("kind")),
                cell(_properties(d)), cell(d["reference"])]
    if kind == "modifiers":
        return [f"[`+{r.id}`]({r.id}.md)", cell(d["doc"]), cell(d["reference"])]
    return [link, cell(d["title"]), cell("yes" if d.get("default") else "no"), cell(d["reference"])]


HEADER = {"problems": ["id", "title", "source", "state", "integrals"],
          "methods": ["id", "what", "order", "kind", "properties", "source"],
          "modifiers": ["id", "what", "source"],
          "metrics": ["id", "what", "default", "source"]}


def index_page(kind: str) -> str:
    rows = [_summary(kind, r) for r in records(kind)]
    return (f"# {TITLE[kind]}\n\n{INTRO[kind]}\n\n" + table(HEADER[kind], rows)
            + "\n```{toctree}\n:hidden:\n:glob:\n\n*\n```\n")


def write(srcdir: Path) -> None:
    """Write ``reference/<kind>/index.md`` and one page per record."""
    for kind in KINDS:
        tree = Tree(srcdir / "reference" / kind)
        tree.write("index.md", index_page(kind))
        for r in records(kind):
            tree.write(f"{r.id}.md", PAGE[kind](r))
        tree.prune()
