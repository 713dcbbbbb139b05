"""The method and modifier registries: one line each. A new method is data in its family's file
plus one line here."""
from gnibench.methods import (
                     compositions,
                     embedded_rk,
                     explicit_rk,
                     external,
                     extrapolation,
                     generating_function,
                     high_order_rk,
                     implicit_rk,
                     lie_poisson,
                     modifiers,
                     partitioned,
                     projection,
                     scipy_methods,
)
from gnibench.suite.foundation.registries import register

METHODS = {m.id: m for m in (
    explicit_rk.euler,
    explicit_rk.rk4,
    embedded_rk.merson,
    embedded_rk.rkf45,
    embedded_rk.dopri5,
    embedded_rk.dop853,
    high_order_rk.vern6,
    high_order_rk.vern7,
    high_order_rk.vern8,
    high_order_rk.vern9,
    high_order_rk.feagin10,
    extrapolation.odex,
    implicit_rk.implicit_euler,
    implicit_rk.implicit_midpoint,
    implicit_rk.gauss4,
    implicit_rk.gauss6,
    partitioned.symplectic_euler,
    partitioned.symplectic_euler_adjoint,
    partitioned.stormer_verlet,
    compositions.yoshida4,
    compositions.yoshida6,
    compositions.yoshida8,
    compositions.suzuki4,
    compositions.mclachlan4,
    compositions.kahan_li6,
    compositions.kahan_li8,
    lie_poisson.lie_poisson,
    generating_function.generating_function4,
    external.heyoka_taylor,
    external.rebound_ias15,
    external.rebound_whfast,
    scipy_methods.scipy_rk45,
    scipy_methods.scipy_rk23,
    scipy_methods.scipy_dop853,
    scipy_methods.scipy_radau,
    scipy_methods.scipy_bdf,
    scipy_methods.scipy_lsoda,
)}

ALIASES = {alias: m.id for m in METHODS.values() for alias in m.aliases}

# The methods that run as compiled gnibench kernels; the external engines (methods/external.py)
# have their own tests (tests/cell/test_reference.py).
COMPILED = {k: m for k, m in METHODS.items() if m.kind == "compiled"}

MODIFIERS = {m.id: m for m in (
    modifiers.observer,
    modifiers.penalty,
    projection.projection,
)}


def lookup_method(id: str):
    """The method record ``id`` (or an alias of it), or None."""
    return METHODS.get(ALIASES.get(id, id))


def lookup_modifier(id: str):
    return MODIFIERS.get(id)


register("method", lookup_method)
register("modifier", lookup_modifier)
