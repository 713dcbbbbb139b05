"""Partitioned methods: symplectic Euler, its adjoint, and Störmer-Verlet as their composition.

[HLW] (1.9): symplectic Euler is implicit in the first block u and explicit in v; its adjoint is
implicit in v. Störmer-Verlet [HLW] (1.17) is the composition (adjoint, h/2) o (symplectic Euler,
h/2), which for a separable H = T(p) + V(q) with blocks (p, q) is exactly (1.17). A block update
is a straight tuple update when the problem's structure makes it explicit (no modifier, and the
block's field does not depend on the block); otherwise Newton solves it (the step writer:
methods/assembly/steps/partitioned.py).
Under ``sum=compensated`` every block update (two per partitioned-Euler step, so four per
Störmer-Verlet step and per stage of a composition) adds its increment with the carried rounding
error ([HLW] VIII.5, methods/summation.py): the ``_sum`` forms ``pstep_u_sum``, ``step_sum``.
"""
from __future__ import annotations

from gnibench.methods.assembly.steps.partitioned import single, stormer_verlet
from gnibench.methods.base import H_PARAM, NEWTON_PARAMS, Method


_PARAMS = (H_PARAM,) + NEWTON_PARAMS

symplectic_euler = Method(
    id="symplectic-euler", family="partitioned", order=1, reference="[HLW] (1.9)",
    doc="symplectic Euler, implicit in the first block u, explicit in v (explicit for separable H)",
    generate=single("u"), params=_PARAMS, symplectic=True, needs=("partition",),
    implicit=True, explicit_when="separable", summation="plain")
symplectic_euler_adjoint = Method(
    id="symplectic-euler-adjoint", family="partitioned", order=1, reference="[HLW] (1.9)",
    doc="adjoint symplectic Euler, implicit in the second block v, explicit in u",
    generate=single("v"), params=_PARAMS, symplectic=True, needs=("partition",),
    implicit=True, explicit_when="separable", summation="plain")
stormer_verlet = Method(
    id="stormer-verlet", family="partitioned", order=2, reference="[HLW] (1.17)",
    doc="Störmer-Verlet / leapfrog: composition of the two symplectic Euler methods with h/2",
    generate=stormer_verlet, params=_PARAMS, symplectic=True, symmetric=True, needs=("partition",),
    implicit=True, explicit_when="separable", summation="plain")
