"""The Lie-Poisson splitting of the Euler equations on so(4) ([B] §7.2; ``splitting`` family).

The splitting, its schedule of exact sub-flows and the round-off argument are
methods/lie_poisson.py; this module writes the six flows (two compensated plane rotations each)
and the step that chains them, unrolled.
"""
from __future__ import annotations

from gnibench.methods.assembly.source import INTERNAL
from gnibench.suite.foundation.errors import UserError

TWO_SUM = """
@internal
def two_sum(a, b):
    # Knuth's error-free sum: s + err == a + b exactly
    s = a + b
    bb = s - a
    return s, (a - (s - bb)) + (b - bb)
"""


def _flow_source(i: int, rotations) -> str:
    """flow_i(y, e, tau, par): the exact flow of (1/2) λ_i x_i² for the time tau, on x = y + e.

    The rotation is applied as x + (s R x - (1 - c) x) with 1 - c = 2 sin²(ωτ/2) (no cancellation),
    and the increment is added by an error-free sum whose error is kept in e (compensated summation,
    reset every step): H1, H2 then see one rounding per coordinate per step, not one per sub-flow.
    """
    (a, b), (c, d) = rotations[i]
    out = ["", INTERNAL, f"def flow_{i}(y, e, tau, par):",
           (f"    # exact flow of (1/2) lam{i + 1} x{i + 1}^2: planes (x{a + 1}, x{b + 1}), "
            f"(x{c + 1}, x{d + 1})"),
           f"    half = 0.5 * par[{i}] * (y[{i}] + e[{i}]) * tau",
           "    sh = math.sin(half)", "    si = 2.0 * sh * math.cos(half)",
           "    vc = 2.0 * sh * sh                  # 1 - cos, without cancellation"]
    for p, q in ((a, b), (c, d)):
        out += [f"    xp = y[{p}] + e[{p}]", f"    xq = y[{q}] + e[{q}]",
                f"    y{p}, e{p} = two_sum(y[{p}], e[{p}] + (si * xq - vc * xp))",
                f"    y{q}, e{q} = two_sum(y[{q}], e[{q}] - (si * xp + vc * xq))"]
    moved = {a, b, c, d}
    ys = ", ".join(f"y{k}" if k in moved else f"y[{k}]" for k in range(6))
    es = ", ".join(f"e{k}" if k in moved else f"e[{k}]" for k in range(6))
    out.append(f"    return ({ys}), ({es})")
    return "\n".join(out) + "\n"


def write_lie_poisson(rotations, schedule):
    """The writer of the splitting's step: ``rotations[i]`` the two planes of sub-flow i,
    ``schedule(order)`` the (sub-flow, fraction of h) of one step (methods/lie_poisson.py)."""
    return lambda ctx: _write(ctx, rotations, schedule)


def _write(ctx, rotations, schedule) -> str:
    if ctx.modified:
        raise UserError("method lie-poisson integrates (7.1) itself by exact sub-flows and cannot "
                        "take a field modifier (observer, penalty); use +projection, or another method")
    plan = schedule(int(ctx.values["order"]))
    body = "".join(f"    y, e = flow_{i}(y, e, {w!r} * h, par)\n" for i, w in plan)
    final = ", ".join(f"y[{k}] + e[{k}]" for k in range(6))
    return (TWO_SUM + "".join(_flow_source(i, rotations) for i in range(6))
            + f"\n{INTERNAL}\ndef make_ws():\n    return 0\n"
            + f"\n{INTERNAL}\ndef step(y, h, par, ws):\n"
            + "    e = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)\n"
            + body + f"    return ({final}), {float(len(plan))!r}, 0.0, STATUS_OK\n")
