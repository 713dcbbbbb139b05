"""The method and modifier registries: one line each. A new method is data in its family's file
plus one line here."""
from methods import explicit_rk, implicit_rk, modifiers, partitioned

METHODS = {m.id: m for m in (
    explicit_rk.euler,
    explicit_rk.rk4,
    implicit_rk.implicit_euler,
    implicit_rk.implicit_midpoint,
    partitioned.symplectic_euler,
    partitioned.symplectic_euler_adjoint,
    partitioned.stormer_verlet,
)}

MODIFIERS = {m.id: m for m in (
    modifiers.observer,
    modifiers.penalty,
)}
