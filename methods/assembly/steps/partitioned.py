"""Partitioned steps (the ``partitioned`` and ``composition`` families): symplectic Euler, its
adjoint, Störmer-Verlet and every composition of them, [HLW] (1.9), (1.17), II.4.

A block update is a straight tuple update when the problem's structure makes it explicit (no
field modifier, and the block's field does not depend on the block: :func:`_explicit_block`, two
half-evaluations of f); otherwise Newton solves it (``block_step`` of templates/partitioned.py, its
index sets I and E given as constant tuples of the module). Under ``sum=compensated`` every block
update adds its increment with the carried rounding error ([HLW] VIII.5): the ``_sum`` forms.
"""
from __future__ import annotations

from gnibench.methods.assembly.source import INLINE, INTERNAL, copy
from gnibench.methods.assembly.templates import partitioned


def _explicit_block(name: str, n: int, i_idx, e_idx) -> str:
    """Tuple code for w1 = w0 + h g_I(y0), e1 = e0 + h g_E(w1, e0): two half-evaluations; and its
    compensated form ``<name>_sum(y, e, h, par, ws)``, each component's increment added with its
    carried error."""
    first = ", ".join(f"y[{i}] + h * g[{i}]" if i in i_idx else f"y[{i}]" for i in range(n))
    second = ", ".join(f"w[{i}] + h * g[{i}]" if i in e_idx else f"w[{i}]" for i in range(n))
    comma = "," if n == 1 else ""
    plain = (f"\n{INTERNAL}\ndef {name}(y, h, par, ws):\n"
             f"    g = f(y, par)\n    w = ({first}{comma})\n    g = f(w, par)\n"
             f"    return ({second}{comma}), 1.0, 0.0, STATUS_OK\n")
    lines = [f"\n{INTERNAL}\ndef {name}_sum(y, e, h, par, ws):", "    g = f(y, par)"]
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
    big = which.upper()
    consts = f"\nI_IDX_{big} = {tup(i_idx)}\nE_IDX_{big} = {tup(e_idx)}\n"
    # the block step of templates/partitioned.py, its index sets given as constant tuples
    src = (consts + f"\n{INTERNAL}\ndef {name}(y, h, par, ws):\n"
           f"    return block_step(y, h, par, ws, I_IDX_{big}, E_IDX_{big})\n"
           f"\n{INTERNAL}\ndef {name}_sum(y, e, h, par, ws):\n"
           f"    return block_step_sum(y, e, h, par, ws, I_IDX_{big}, E_IDX_{big})\n")
    return src, f"block_ws({len(i_idx)})"


def _newton_blocks(*parts: tuple[str, str]) -> str:
    """The Newton block step (templates/partitioned.py), when a block of the cell is implicit."""
    if not any(ws.startswith("block_ws") for _, ws in parts):
        return ""
    return "".join(copy(fn, INLINE) for fn in (partitioned.block_ws, partitioned.block_step,
                                               partitioned.block_step_sum))


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
        out += [f"\n{INTERNAL}\ndef {name}(y, {'e, ' if carry else ''}h, par, ws):",
                "    nf = 0.0", "    nj = 0.0", f"    stages = int(par[{at}])"]
        out += _compose_block("u", "1", at, carry, "    ")
        out.append("    for i in range(1, stages):")
        out += (_compose_block("v", "2 * i", at, carry, "        ")
                + _compose_block("u", "2 * i + 1", at, carry, "        "))
        out += _compose_block("v", "2 * stages", at, carry, "    ")
        out.append(f"    return y, {'e, ' if carry else ''}nf, nj, STATUS_OK")
    return "\n".join(out) + "\n"


def single(which: str):
    def generate(ctx) -> str:
        src, ws = _block(ctx, which)
        return (src + _newton_blocks((src, ws)) + f"\n{INTERNAL}\ndef make_ws():\n    return {ws}\n"
                f"\n{INTERNAL}\ndef step(y, h, par, ws):\n    return pstep_{which}(y, h, par, ws)\n"
                f"\n{INTERNAL}\ndef step_sum(y, e, h, par, ws):\n"
                f"    return pstep_{which}_sum(y, e, h, par, ws)\n")
    return generate


def stormer_verlet(ctx) -> str:
    src_u, ws_u = _block(ctx, "u")
    src_v, ws_v = _block(ctx, "v")
    return (src_u + src_v + _newton_blocks((src_u, ws_u), (src_v, ws_v))
            + f"\n{INTERNAL}\ndef make_ws():\n    return ({ws_u}, {ws_v})\n"
            f"\n{INTERNAL}\ndef step(y, h, par, ws):\n"
            "    # [HLW] (1.17) = adjoint(h/2) o symplectic Euler(h/2)\n"
            "    y1, n1, j1, s1 = pstep_u(y, 0.5 * h, par, ws[0])\n"
            "    if s1 != STATUS_OK:\n        return y, n1, j1, s1\n"
            "    y2, n2, j2, s2 = pstep_v(y1, 0.5 * h, par, ws[1])\n"
            "    return y2, n1 + n2, j1 + j2, s2\n"
            f"\n{INTERNAL}\ndef step_sum(y, e, h, par, ws):\n"
            "    y1, e1, n1, j1, s1 = pstep_u_sum(y, e, 0.5 * h, par, ws[0])\n"
            "    if s1 != STATUS_OK:\n        return y, e, n1, j1, s1\n"
            "    y2, e2, n2, j2, s2 = pstep_v_sum(y1, e1, 0.5 * h, par, ws[1])\n"
            "    return y2, e2, n1 + n2, j1 + j2, s2\n")


def composed_step(ctx) -> str:
    """The step of every composition of Störmer-Verlet or of symplectic Euler and its adjoint (a
    user's too, suite/cell/user/methods.py): its coefficients are read from ``par``
    (``runtime_data``)."""
    src_u, ws_u = _block(ctx, "u")
    src_v, ws_v = _block(ctx, "v")
    return (src_u + src_v + _newton_blocks((src_u, ws_u), (src_v, ws_v))
            + f"\n{INTERNAL}\ndef make_ws():\n    return ({ws_u}, {ws_v})\n"
            + compose(ctx.extra["data_at"]))
