"""Statistics of Poincaré section points: counts per chart, and how many lie near a point.

[B] §6.2 (Fig 18), ODEX with the simple observer on the Gavrilov-Shil'nikov system: the orbit
"goes only few times along the homoclinic loop, and after that it oscillates very close to the
equilibrium point ... almost 90% points in Figure 18 lie in a very small neighbourhood". The
fraction of section points within a radius δ of a point measures that (the radius is a gap of the
seed; claim B-6.2-d proposes δ = 1e-3, the default here). [B] §7 (Figs 26-30) draws the so(4)
section in its charts Γ1..Γ8; the points per chart say where an orbit's crossings went.

Distances are Euclidean, in the section's recorded coordinates (``space=section``: what the
figures plot, e.g. (q2, p2) for G-S, (x5, x6) for so(4)) or in the full state (``space=state``,
the ‖x‖ < δ of the claims inventory). The default point is the origin of that space, which is the
equilibrium x = 0 of G-S [B] (6.1).
"""
from __future__ import annotations

import numpy as np
from gnibench.suite.foundation.params import Param
from gnibench.suite.metrics.base import Metric, MetricOutput


def section_coordinates(traj, space: str) -> np.ndarray:
    """The section points in the chosen space: the recorded section coordinates or the state."""
    if space == "state":
        return traj.y
    coords = list(traj.provenance.get("section_coords", ()))
    return traj.y[:, [traj.state_names.index(c) for c in coords]]


def chart_counts(chart: np.ndarray | None, charts: int) -> dict[int, int]:
    """Points per chart k = 1..charts (and any chart index beyond, should one occur)."""
    if chart is None:
        return {}
    chart = np.asarray(chart, dtype=np.int64)
    top = max(charts, int(chart.max()) if len(chart) else 0)
    counts = np.bincount(chart, minlength=top + 1)
    return {k: int(counts[k]) for k in range(1, top + 1)}


def _point(values, dim: int) -> np.ndarray | str:
    point = values["point"]
    if point is None:
        return np.zeros(dim)
    if len(point) != dim:
        return f"point has {len(point)} coordinates; the {values['space']} space has {dim}"
    return np.asarray(point, dtype=float)


def _compute(traj, problem, values) -> MetricOutput:
    x = section_coordinates(traj, values["space"])
    point = _point(values, x.shape[1])
    distance = np.linalg.norm(x - point[None, :], axis=1)
    within = int(np.sum(distance < values["radius"]))
    total = len(traj.t)
    out = MetricOutput(columns={"section_distance": distance})
    out.scalars.update({"section_points": total, "section_points_within": within,
                        "section_fraction_within": within / total if total else float("nan")})
    charts = next((s.charts for s in problem.record.sections if s.chart is not None), 0)
    for k, count in chart_counts(traj.chart, charts).items():
        out.scalars[f"section_points_chart{k}"] = count
    return out


def _check(traj, problem, values) -> str:
    if values["space"] == "section" and not traj.provenance.get("section_coords"):
        return "the trajectory does not record its section coordinates"
    dim = (traj.y.shape[1] if values["space"] == "state"
           else len(traj.provenance["section_coords"]))
    bad = _point(values, dim)
    return bad if isinstance(bad, str) else ""


section_stats = Metric(
    id="section_stats", title="section points: counts per chart, fraction within a radius",
    reference="[B] §6.2 (Fig 18), §7 (Figs 26-30); claim B-6.2-d",
    doc=("number of section points, per chart (Γ1..Γk of multi-chart sections such as so(4)), "
         "their distance to a point (default: the origin, G-S's equilibrium) and the fraction "
         "within a radius"),
    compute=_compute, needs=("section",),
    params=(Param("radius", 1e-3, "radius δ of the neighbourhood (claim B-6.2-d proposes "
                  "1e-3)", low=0.0, low_open=True),
            Param("point", None, "centre of the neighbourhood, in the coordinates of the space "
                  "(default: the origin)", kind="floats"),
            Param("space", "section", "section: the recorded section coordinates; state: the "
                  "full state", kind="str", choices=("section", "state"))),
    columns=(("section_distance", "distance of the point to the centre, in the chosen space"),),
    scalars=(("section_points", "number of section points"),
             ("section_points_within", "points at distance < radius"),
             ("section_fraction_within", "their fraction of all points"),
             ("section_points_chart<k>", ("points in chart Γk, k = 1..charts (multi-chart "
                                         "sections)"))),
    check=_check,
)
