"""Partitioned methods: symplectic Euler, its adjoint, and Störmer-Verlet as their composition.

[HLW] (1.9): symplectic Euler is implicit in the first block u and explicit in v; its adjoint is
implicit in v. Störmer-Verlet [HLW] (1.17) is the composition (adjoint, h/2) o (symplectic Euler,
h/2), which for a separable H = T(p) + V(q) with blocks (p, q) is exactly (1.17). A block update
is a straight tuple update when the problem's structure makes it explicit (no modifier, and the
block's field does not depend on the block); otherwise Newton solves it (kernels/partitioned.py).
Under ``sum=compensated`` every block update (two per partitioned-Euler step, so four per
Störmer-Verlet step and per stage of a composition) adds its increment with the carried rounding
error ([HLW] VIII.5, methods/summation.py): the ``_sum`` forms ``pstep_u_sum``, ``step_sum``.
"""
from __future__ import annotations

from gnibench.methods.base import H_PARAM, NEWTON_PARAMS, Method
from gnibench.methods.kernels import partitioned
from gnibench.suite.foundation.templates import template


def _explicit_block(name: str, n: int, i_idx, e_idx) -> str:
    """Tuple code for w1 = w0 + h g_I(y0), e1 = e0 + h g_E(w1, e0): two half-evaluations; and its
    compensated form ``<name>_sum(y, e, h, par, ws)``, each component's increment added with its
    carried error."""
    first = ", ".join(f"y[{i}] + h * g[{i}]" if i in i_idx else f"y[{i}]" for i in range(n))
    second = ", ".join(f"w[{i}] + h * g[{i}]" if i in e_idx else f"w[{i}]" for i in range(n))
    comma = "," if n == 1 else ""
    plain = (f"\n@njit(cache=True)\ndef {name}(y, h, par, ws):\n"
             f"    g = f(y, par)\n    w = ({first}{comma})\n    g = f(w, par)\n"
             f"    return ({second}{comma}), 1.0, 0.0, STATUS_OK\n")
    lines = [f"\n@njit(cache=True)\ndef {name}_sum(y, e, h, par, ws):", "    g = f(y, par)"]
    for i in range(n):
        lines.append(f"    w{i}, c{i} = carry_sum(y[{i}], e[{i}], h * g[{i}])" if i in i_idx
                     else f"    w{i}, c{i} = y[{i}], e[{i}]")
    lines.append(f"    g = f(({', '.join(f'w{i}' for i in range(n))}{comma}), par)")
    for i in e_idx:
        lines.append(f"    w{i}, c{i} = carry_sum(w{i}, c{i}, h * g[{i}])")
    lines.append(f"    return ({', '.join(f'w{i}' for i in range(n))}{comma}), "
                 f"({', '.join(f'c{i}' for i in range(n))}{comma}), 1.0, 0.0, STATUS_OK")
    return plain + "\n".join(lines) + "\n"


def _block(ctx, which: str) -> tuple[str, str]:
    """Source of one partitioned-Euler step implicit in block ``which`` ('u' or 'v'), and its
    compensated form ``pstep_<which>_sum``."""
    u, v = ctx.meta["u_idx"], ctx.meta["v_idx"]
    i_idx, e_idx = (u, v) if which == "u" else (v, u)
    explicit = ctx.explicit_u if which == "u" else ctx.explicit_v
    name = f"pstep_{which}"
    if explicit:
        return _explicit_block(name, ctx.n, i_idx, e_idx), "0"
    tup = lambda xs: "(" + ", ".join(str(x) for x in xs) + ",)"
    consts = (f"\nNI_{which} = {len(i_idx)}\nNE_{which} = {len(e_idx)}\n"
              f"I_IDX_{which} = {tup(i_idx)}\nE_IDX_{which} = {tup(e_idx)}\n")
    rename = {"make_ws_X": f"make_ws_{which}", "step_X_sum": f"{name}_sum", "step_X": name,
              "NI": f"NI_{which}", "NE": f"NE_{which}", "I_IDX": f"I_IDX_{which}",
              "E_IDX": f"E_IDX_{which}"}
    src = consts + "".join(template(fn, rename) for fn in (partitioned.make_ws_X,
                                                           partitioned.step_X,
                                                           partitioned.step_X_sum))
    return src, f"make_ws_{which}()"


def _compose_block(which: str, k: str, at: int, carry: bool, indent: str) -> list[str]:
    """One block step of a composed stage, its coefficient of h read from ``par[at + k]``."""
    call = (f"y, e, a, b, s = pstep_{which}_sum(y, e, " if carry
            else f"y, a, b, s = pstep_{which}(y, ")
    ret = "y, e, nf, nj, s" if carry else "y, nf, nj, s"
    return [f"{indent}{call}par[{at} + {k}] * h, par, ws[{0 if which == 'u' else 1}])",
            f"{indent}nf += a", f"{indent}nj += b", f"{indent}if s != STATUS_OK:",
            f"{indent}    return {ret}"]


def compose(at: int) -> str:
    """``step(y, h, par, ws)`` chaining s stages of the two block steps, Φ*_{b_s h} ∘ Φ_{a_s h} ∘ …
    ∘ Φ*_{b_1 h} ∘ Φ_{a_1 h}, with s = par[at] and (a_i, b_i) = (par[at + 2i - 1], par[at + 2i])
    read at run time (``Method.runtime_data``): every composition of a problem shares this one
    kernel; one stage with a = b = 1/2 is Störmer-Verlet, [HLW] (1.17). The loop runs from the
    middle of one stage to the middle of the next (Φ* of stage i, then Φ of stage i + 1), so that
    LLVM sees the two block steps on either side of a stage boundary together, as in the stages
    written out (measured, yoshida4 on kepler-2d: 3 % slower than written out, 5 % with a loop
    over whole stages; the longer compositions as fast). For ``sum=compensated``,
    ``step_sum(y, e, h, par, ws)`` carries e through every block."""
    out = []
    for name, carry in (("step", False), ("step_sum", True)):
        out += [f"\n@njit(cache=True)\ndef {name}(y, {'e, ' if carry else ''}h, par, ws):",
                "    nf = 0.0", "    nj = 0.0", f"    stages = int(par[{at}])"]
        out += _compose_block("u", "1", at, carry, "    ")
        out.append("    for i in range(1, stages):")
        out += (_compose_block("v", "2 * i", at, carry, "        ")
                + _compose_block("u", "2 * i + 1", at, carry, "        "))
        out += _compose_block("v", "2 * stages", at, carry, "    ")
        out.append(f"    return y, {'e, ' if carry else ''}nf, nj, STATUS_OK")
    return "\n".join(out) + "\n"


def _single(which: str):
    def generate(ctx) -> str:
        src, ws = _block(ctx, which)
        return (src + f"\n@njit(cache=True)\ndef make_ws():\n    return {ws}\n"
                f"\n@njit(cache=True)\ndef step(y, h, par, ws):\n    return pstep_{which}(y, h, par, ws)\n"
                f"\n@njit(cache=True)\ndef step_sum(y, e, h, par, ws):\n"
                f"    return pstep_{which}_sum(y, e, h, par, ws)\n")
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
            "    return y2, n1 + n2, j1 + j2, s2\n"
            "\n@njit(cache=True)\ndef step_sum(y, e, h, par, ws):\n"
            "    y1, e1, n1, j1, s1 = pstep_u_sum(y, e, 0.5 * h, par, ws[0])\n"
            "    if s1 != STATUS_OK:\n        return y, e, n1, j1, s1\n"
            "    y2, e2, n2, j2, s2 = pstep_v_sum(y1, e1, 0.5 * h, par, ws[1])\n"
            "    return y2, e2, n1 + n2, j1 + j2, s2\n")


_PARAMS = (H_PARAM,) + NEWTON_PARAMS

symplectic_euler = Method(
    id="symplectic-euler", family="partitioned", order=1, reference="[HLW] (1.9)",
    doc="symplectic Euler, implicit in the first block u, explicit in v (explicit for separable H)",
    generate=_single("u"), params=_PARAMS, symplectic=True, needs=("partition",),
    implicit=True, explicit_when="separable", summation="plain")
symplectic_euler_adjoint = Method(
    id="symplectic-euler-adjoint", family="partitioned", order=1, reference="[HLW] (1.9)",
    doc="adjoint symplectic Euler, implicit in the second block v, explicit in u",
    generate=_single("v"), params=_PARAMS, symplectic=True, needs=("partition",),
    implicit=True, explicit_when="separable", summation="plain")
stormer_verlet = Method(
    id="stormer-verlet", family="partitioned", order=2, reference="[HLW] (1.17)",
    doc="Störmer-Verlet / leapfrog: composition of the two symplectic Euler methods with h/2",
    generate=_stormer_verlet, params=_PARAMS, symplectic=True, symmetric=True, needs=("partition",),
    implicit=True, explicit_when="separable", summation="plain")
