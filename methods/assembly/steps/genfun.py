"""The generating-function method (``generating-function`` family, [B] §8.2): Newton on P.

The maps of the step (the starting guess, the momentum equation with its Jacobian, the new
position) are derived by sympy from the problem's Hamiltonian and printed as numba source by
methods/generating_function.py (cached on disk); the step is templates/genfun.py.
"""
from __future__ import annotations

from gnibench.methods.assembly.source import copy
from gnibench.methods.assembly.templates import genfun
from gnibench.suite.foundation.errors import UserError


def write_genfun(generating_code, generating_key):
    """The writer of the method's step; ``generating_code(problem)`` gives the maps' text (from
    sympy, cached), ``generating_key(problem)`` the digest of what it is made from."""
    return lambda ctx: _write(ctx, generating_code, generating_key)


def _write(ctx, generating_code, generating_key) -> str:
    if ctx.modified:        # refused at validation (field_modifiers_refused); a modified field has no H
        raise UserError("method generating-function4 cannot take a field modifier (observer, penalty)")
    problem = ctx.problem
    # for the kernel key, the digest of what the text is made from: sympy takes seconds
    code = f"# {generating_key(problem)}\n" if ctx.keyed else generating_code(problem)
    return (f"\nD = {len(problem.canonical[0])}\n" + code
            + copy(genfun.make_ws) + copy(genfun.step))
