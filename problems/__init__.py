"""The problem registry: one line per problem. A new problem is one file plus one line here."""
from gnibench.problems import (
    double_oscillator,
    euler_so4,
    gavrilov_shilnikov,
    gavrilov_shilnikov_modified,
    geodesic_genus2,
    harmonic_oscillator,
    heavy_top_hess,
    henon_heiles,
    kepler_2d,
    kepler_3d,
    kepler_radial,
    lotka_volterra,
    outer_solar_system,
    pendulum,
)
from gnibench.suite.foundation.registries import register

REGISTRY = {m.PROBLEM.id: m.PROBLEM for m in (
    harmonic_oscillator,
    double_oscillator,
    pendulum,
    kepler_2d,
    lotka_volterra,
    kepler_radial,
    kepler_3d,
    outer_solar_system,
    henon_heiles,
    gavrilov_shilnikov,
    gavrilov_shilnikov_modified,
    euler_so4,
    geodesic_genus2,
    heavy_top_hess,
)}

#: problems reached only through a transform of a registered one (K-S): not listed, but a cell
#: of the transformed system refers to them
INTERNAL = {p.transform.problem.id: p.transform.problem for p in REGISTRY.values()
            if p.transform is not None}


def lookup(id: str):
    """The problem record ``id`` (registered or internal), or None."""
    return REGISTRY.get(id) or INTERNAL.get(id)


register("problem", lookup)
