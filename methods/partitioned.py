"""Partitioned methods: symplectic Euler, its adjoint, and Störmer-Verlet as their composition.

[HLW] (1.9): symplectic Euler is implicit in the first block u and explicit in v; its adjoint is
implicit in v. Störmer-Verlet [HLW] (1.17) is the composition (adjoint, h/2) o (symplectic Euler,
h/2), which for a separable H = T(p) + V(q) with blocks (p, q) is exactly (1.17). A block update
is a straight tuple update when the problem's structure makes it explicit (no modifier, and the
block's field does not depend on the block); otherwise Newton solves it (kernels/partitioned.py).
"""
from __future__ import annotations

from gnibench.methods.base import H_PARAM, NEWTON_PARAMS, Method
from gnibench.methods.kernels import partitioned
from gnibench.suite.foundation.templates import template


def _explicit_block(name: str, n: int, i_idx, e_idx) -> str:
    """Tuple code for w1 = w0 + h g_I(y0), e1 = e0 + h g_E(w1, e0): two half-evaluations."""
    first = ", ".join(f"y[{i}] + h * g[{i}]" if i in i_idx else f"y[{i}]" for i in range(n))
    second = ", ".join(f"w[{i}] + h * g[{i}]" if i in e_idx else f"w[{i}]" for i in range(n))
    comma = "," if n == 1 else ""
    return (f"\n@njit(cache=True)\ndef {name}(y, h, par, ws):\n"
            f"    g = f(y, par)\n    w = ({first}{comma})\n    g = f(w, par)\n"
            f"    return ({second}{comma}), 1.0, 0.0, STATUS_OK\n")


def _block(ctx, which: str) -> tuple[str, str]:
    """Source of one partitioned-Euler step implicit in block ``which`` ('u' or 'v')."""
    u, v = ctx.meta["u_idx"], ctx.meta["v_idx"]
    i_idx, e_idx = (u, v) if which == "u" else (v, u)
    explicit = ctx.explicit_u if which == "u" else ctx.explicit_v
    name = f"pstep_{which}"
    if explicit:
        return _explicit_block(name, ctx.n, i_idx, e_idx), "0"
    tup = lambda xs: "(" + ", ".join(str(x) for x in xs) + ",)"
    consts = (f"\nNI_{which} = {len(i_idx)}\nNE_{which} = {len(e_idx)}\n"
              f"I_IDX_{which} = {tup(i_idx)}\nE_IDX_{which} = {tup(e_idx)}\n")
    rename = {"make_ws_X": f"make_ws_{which}", "step_X": name, "NI": f"NI_{which}",
              "NE": f"NE_{which}", "I_IDX": f"I_IDX_{which}", "E_IDX": f"E_IDX_{which}"}
    src = consts + template(partitioned.make_ws_X, rename) + template(partitioned.step_X, rename)
    return src, f"make_ws_{which}()"


def _single(which: str):
    def generate(ctx) -> str:
        src, ws = _block(ctx, which)
        return (src + f"\n@njit(cache=True)\ndef make_ws():\n    return {ws}\n"
                f"\n@njit(cache=True)\ndef step(y, h, par, ws):\n    return pstep_{which}(y, h, par, ws)\n")
    return generate


def _stormer_verlet(ctx) -> str:
    src_u, ws_u = _block(ctx, "u")
    src_v, ws_v = _block(ctx, "v")
    return (src_u + src_v + f"\n@njit(cache=True)\ndef make_ws():\n    return ({ws_u}, {ws_v})\n"
            "\n@njit(cache=True)\ndef step(y, h, par, ws):\n"
            "    # [HLW] (1.17) = adjoint(h/2) o symplectic Euler(h/2)\n"
            "    y1, n1, j1, s1 = pstep_u(y, 0.5 * h, par, ws[0])\n"
            "    if s1 != STATUS_OK:\n        return y, n1, j1, s1\n"
            "    y2, n2, j2, s2 = pstep_v(y1, 0.5 * h, par, ws[1])\n"
            "    return y2, n1 + n2, j1 + j2, s2\n")


_PARAMS = (H_PARAM,) + NEWTON_PARAMS

symplectic_euler = Method(
    id="symplectic-euler", family="partitioned", order=1, reference="[HLW] (1.9)",
    doc="symplectic Euler, implicit in the first block u, explicit in v (explicit for separable H)",
    generate=_single("u"), params=_PARAMS, symplectic=True, needs=("partition",),
    implicit=True, explicit_when="separable")
symplectic_euler_adjoint = Method(
    id="symplectic-euler-adjoint", family="partitioned", order=1, reference="[HLW] (1.9)",
    doc="adjoint symplectic Euler, implicit in the second block v, explicit in u",
    generate=_single("v"), params=_PARAMS, symplectic=True, needs=("partition",),
    implicit=True, explicit_when="separable")
stormer_verlet = Method(
    id="stormer-verlet", family="partitioned", order=2, reference="[HLW] (1.17)",
    doc="Störmer-Verlet / leapfrog: composition of the two symplectic Euler methods with h/2",
    generate=_stormer_verlet, params=_PARAMS, symplectic=True, symmetric=True, needs=("partition",),
    implicit=True, explicit_when="separable")
