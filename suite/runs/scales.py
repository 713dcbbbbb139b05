"""Two scales of one experiment file, and sets of initial points.

**Scales.** The top-level and group values of an experiment file are the ``paper`` scale: the
seed's horizons and step sizes. A file may state a shortened ``quick`` scale (and, rarely, change
the paper one) with overrides::

    [scale.quick]                  # top level: replaces t_end | steps, every, section
    t_end = 62.8
    every = 10

    [[cells]]
    ...
    [cells.scale.quick]            # one group: t_end | steps, every, section, vary.<...>, points.<...>
    steps = 200
    vary.h = [0.01, 0.005]         # replaces vary.h only (other vary keys stay)
    points.n = 40                  # replaces n of the group's point set

A horizon given in a scale (``t_end`` or ``steps``) replaces the horizon at the same level (both
keys); ``every`` replaces ``every``; ``vary`` and ``points`` are merged key by key. A group that
states its own horizon keeps it at every scale unless its own ``[cells.scale.<name>]`` changes
it. A scale the file does not state is the paper scale.

**Point sets.** A group's ``points`` is an ensemble cell (:mod:`gnibench.suite.runs.ensemble_spec`)
whose orbits' samples are all kept (the flow of a set, [HLW] Figs 1.1 and 1.3): the points set
the problem options named in ``options``, in order::

    [cells.points]
    options = ["q0", "p0"]                                   # problem options, one per coordinate
    circle = { center = [0.0, 1.5], radius = 0.4, n = 60 }   # or
    polygon = { vertices = [[1, 2], [3, 2], [2, 4]], n = 90 } # evenly spaced along the outline, or
    list = [[1.0, 2.0], [1.5, 2.5]]

The keys, their types and bounds are in :mod:`gnibench.suite.runs.experiment_schema` (``ScaleTop``,
``ScaleGroup``, ``Points``, ``Circle``, ``Polygon``, ``Ensemble``). The orbits of a point set are
numbered in the order of the points (counterclockwise for a circle, along the vertices for a
polygon), so the drawing can join them into the image of the outline.
"""
from __future__ import annotations

import copy

from gnibench.suite.foundation.errors import unknown

SCALES = ("paper", "quick")


def check_scale(scale: str) -> str:
    if scale not in SCALES:
        raise unknown("scale", scale, SCALES)
    return scale


def scales_stated(doc: dict) -> tuple[str, ...]:
    """The scales a parsed file states beside the paper one (at the top or in a group)."""
    named = set(doc.get("scale", {}) if isinstance(doc.get("scale"), dict) else ())
    for group in doc.get("cells", []) if isinstance(doc.get("cells"), list) else []:
        if isinstance(group, dict) and isinstance(group.get("scale"), dict):
            named |= set(group["scale"])
    return tuple(s for s in SCALES if s in named or s == "paper")


def at_scale(doc: dict, scale: str) -> dict:
    """The parsed file with the overrides of ``scale`` applied and every ``scale`` table removed.
    The file has been validated as a whole before (:mod:`gnibench.suite.runs.experiment_schema`:
    the overrides of every scale are checked, so a bad one is found whichever runs)."""
    check_scale(scale)
    doc = copy.deepcopy(doc)
    _override(doc, doc.pop("scale", {}).get(scale, {}))
    for group in doc.get("cells", []):
        _override(group, group.pop("scale", {}).get(scale, {}))
    return doc


def _override(table: dict, changes: dict) -> None:
    if "t_end" in changes or "steps" in changes:
        table.pop("t_end", None)
        table.pop("steps", None)
    for key, value in changes.items():
        if key in ("vary", "points", "ensemble") and isinstance(table.get(key), dict):
            merged = table[key]
            for k, v in value.items():
                if isinstance(v, dict) and isinstance(merged.get(k), dict):
                    merged[k] = {**merged[k], **v}
                else:
                    merged[k] = v
        else:
            table[key] = value
