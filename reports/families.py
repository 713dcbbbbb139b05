"""Method families: the cells of one method that differ only in its step size or tolerance.

A work-precision curve or a league-table row is one family: the canonical method spec without its
sweep options (``h``; ``rtol``/``atol``; ``tol``; ``epsilon``) and without options left at their
defaults, e.g. ``dopri5:adaptive=true,rtol=1e-08,atol=1e-08`` -> ``dopri5``,
``merson:adaptive=true,rtol=1e-05,atol=1e-05`` -> ``merson:adaptive=true``,
``heyoka-taylor:dt_out=0.01,tol=1e-10,precision=long double`` -> ``heyoka-taylor:precision=long
double`` (a step budget ``max_steps`` and an output grid ``dt_out`` are left out too). Modifiers stay part
of the family.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

#: options a work-precision sweep varies: they do not name a family
SWEEP = ("h", "rtol", "atol", "tol", "epsilon")
#: options that do not change a method's numbers (a step budget, the output grid of external
#: engines): left out of the family's label
QUIET = ("max_steps", "dt_out")


@dataclass(frozen=True)
class Family:
    """A method spec split into its family label, the swept option and its value."""

    label: str
    sweep: str                 # "h", "rtol", "tol", "epsilon" or "" (nothing swept)
    value: float               # its value (NaN when nothing is swept)
    adaptive: bool
    base: str


def _default_texts(base: str) -> dict[str, str]:
    from gnibench.methods import METHODS

    record = METHODS.get(base)
    if record is None:
        return {}
    out = {}
    for p in record.params:
        d = p.default
        out[p.name] = str(d).lower() if isinstance(d, bool) else ("" if d is None else str(d))
    return out


def _engine_adaptive(base: str) -> bool:
    """An external engine that chooses its own steps (heyoka, IAS15, scipy's solvers)."""
    from gnibench.methods import METHODS

    return bool(getattr(METHODS.get(base), "adaptive", False))


def _same(text: str, default: str) -> bool:
    try:
        return math.isclose(float(text), float(default), rel_tol=0, abs_tol=0)
    except ValueError:
        return text.strip().lower() == default.strip().lower()


def family_of(method: str) -> Family:
    """The family of a canonical method spec (see the module docstring)."""
    from gnibench.suite.cell.spec import Item, Structure, structure

    spec = structure(method)
    base, given = spec.id, spec.base.given
    defaults = _default_texts(base)
    adaptive = given.get("adaptive", defaults.get("adaptive", "false")).lower() == "true" or \
        _engine_adaptive(base)
    sweep = next((k for k in ("h", "rtol", "tol", "epsilon") if k in given), "")
    if sweep == "h" and adaptive:
        sweep = ""
    keep = {k: v for k, v in given.items()
            if k not in SWEEP and k not in QUIET and not (k in defaults and _same(v, defaults[k]))}
    label = Structure(Item(base, tuple(keep.items())), spec.modifiers).text()
    try:
        value = float(given[sweep]) if sweep else float("nan")
    except ValueError:
        value = float("nan")
    return Family(label, sweep, value, adaptive, base)


def kind_of(base: str) -> str:
    """How a shipped method runs (``compiled``, ``external``), for tables written before the
    column ``method_kind``; a method this process does not know is ``compiled``."""
    from gnibench.methods import lookup_method

    record = lookup_method(base)
    return record.kind if record is not None else "compiled"


def add_families(cells):
    """The cells table with columns ``family``, ``sweep``, ``sweep_value``, ``adaptive``,
    ``base_method``, ``modifiers``, ``problem_id`` and ``method_kind`` (how the method runs: the
    table's column, else the registry's); tables written before the columns ``swept`` and
    ``setup_method`` get them from the family (the method without its sweep option)."""
    from gnibench.suite.cell.spec import structure

    fams = [family_of(m) for m in cells["method"]]
    out = cells.copy()
    out["family"] = [f.label for f in fams]
    out["sweep"] = [f.sweep for f in fams]
    out["sweep_value"] = [f.value for f in fams]
    out["adaptive"] = [f.adaptive for f in fams]
    parts = [structure(m) for m in cells["method"]]
    if "base_method" not in out:
        out["base_method"] = [p.id for p in parts]
    if "modifiers" not in out:
        out["modifiers"] = ["+".join(m.id for m in p.modifiers) for p in parts]
    if "problem_id" not in out:
        out["problem_id"] = [structure(p, "problem").id for p in cells["problem"]]
    if "method_kind" not in out:
        out["method_kind"] = [kind_of(f.base) for f in fams]
    if "swept" not in out:
        out["swept"] = [f.sweep for f in fams]
    if "setup_method" not in out:
        out["setup_method"] = [p.without(f.sweep).text() if f.sweep else p.text()
                               for p, f in zip(parts, fams)]
    return out
