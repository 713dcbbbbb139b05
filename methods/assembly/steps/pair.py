"""Embedded Runge-Kutta pairs (the ``embedded-rk`` family): their fixed step and their attempt.

Fixed step (``adaptive=false``): the propagated solution, written by
:func:`gnibench.methods.assembly.steps.erk.write_erk`. Adaptive: the pair's part of the adaptive loop
(templates/adaptive.py): ``attempt`` (y1, its carry, the scaled rms error and f(y1) when the pair
has it) and ``attempt_stages`` (the very same lines, also returning the stages for the continuous
extension, so y1 and err are the same bit for bit), written from the tableau; Hairer's controller
(templates/pair.py) and HINIT (templates/adaptive.py) copied; the continuous extension
(steps/dense.py) when the pair has one. Under ``sum=compensated`` the attempt adds the increment
h Σ b_i k_i to y with the carried rounding error (methods/summation.py).
"""
from __future__ import annotations

from gnibench.methods.assembly.source import ENTRY, INLINE, INTERNAL, constants, copy, tup
from gnibench.methods.assembly.steps.dense import generate_dense
from gnibench.methods.assembly.steps.erk import combination, increment, stage_lines, write_erk
from gnibench.methods.assembly.templates import adaptive, pair as controller
from gnibench.methods.summation import compensated
from gnibench.methods.tableau import lit

#: Hairer's controller and the pair's small parts of the loop, copied from templates/pair.py (the
#: small ones written into the loop by numba's inliner) and HINIT from templates/adaptive.py
CONTROLLER = ((controller.adaptive_ws, INLINE), (controller.controller_init, INLINE),
              (controller.controller_state, INLINE), (controller.controller_clip, INLINE),
              (controller.controller_prepare, INLINE), (controller.attempt_outcome, INLINE),
              (controller.controller_accept, INLINE), (controller.controller_reject, INLINE),
              (controller.dense_coeffs, ENTRY), (controller.partial_step, INTERNAL),
              (adaptive.initial_step, INLINE), (adaptive.first_step, INLINE))


def _error_lines(pair: Pair, n: int) -> list[str]:
    """Scaled rms error of the step; DOP853 combines its 5th- and 3rd-order estimates."""
    def comb(w, i):
        return " + ".join(f"{lit(c)} * k{j}[{i}]" for j, c in enumerate(w) if c != 0)

    lines = ["    acc = 0.0", "    acc3 = 0.0"]
    for i in range(n):
        lines.append(f"    sk = atol + rtol * max(abs(y[{i}]), abs(y1[{i}]))")
        if pair.e3 is None:
            lines.append(f"    acc += (h * ({comb(pair.e, i)}) / sk) ** 2")
        else:
            lines.append(f"    acc += (({comb(pair.e, i)}) / sk) ** 2")
            lines.append(f"    acc3 += (({comb(pair.e3, i)}) / sk) ** 2")
    if pair.e3 is None:
        lines.append(f"    err = math.sqrt(acc / {n})")
    else:  # DOP853: err = |h| err5^2 / sqrt(n (err5^2 + 0.01 err3^2))
        lines += ["    deno = acc + 0.01 * acc3",
                  "    if deno <= 0.0:", "        deno = 1.0",
                  f"    err = abs(h) * acc / math.sqrt(deno * {n})"]
    return lines


def write_attempt(data, ctx) -> str:
    """The pair's adaptive part: its constants, ``to_tuple_shift``, ``attempt``,
    ``attempt_stages``, the controller, and the continuous extension when the pair has one."""
    n, s, tab = ctx.n, data.tab.stages, data.tab
    count = s - 1 if data.fsal else s
    stages = stage_lines(tab, count, n, first="k0")
    fsal = data.fsal and not data.lazy_last
    knew = f"k{s - 1}" if fsal else "k0"  # else the loop evaluates f(y1) once accepted
    if compensated(ctx.values):     # the increment h Σ b_i k_i added with the carried error
        inc = increment(tab.doubles[1], n)
        new_y, carry = [f"    y1, e1 = carry_add(y, e, {inc})"], "e1"
    else:
        new_y, carry = [f"    y1 = {combination(tab.doubles[1], n)}"], "e"
    lines = (stages + new_y + ([f"    k{s - 1} = f(y1, par)"] if fsal else [])
             + _error_lines(data, n))
    head = "(y, e, k0, h, par, ws, rtol, atol):"
    ks = ", ".join(f"k{j}" for j in range(count)) + ("," if count == 1 else "")
    body = ([f"\n{INTERNAL}\ndef attempt" + head] + lines
            + [f"    return y1, {carry}, err, {knew}"]
            + [f"\n{INTERNAL}\ndef attempt_stages" + head] + lines
            + [f"    return y1, {carry}, err, {knew}, ({ks})"])
    dense = ""
    dense_nfev = 0.0
    if data.dense is not None:
        dense = generate_dense(data.dense, tab, count, n)
        dense_nfev = float(data.dense.new_stages(tab))
    consts = constants(FSAL=fsal, STAGES_NEW=float(count - 1 + fsal), IORD=data.iord,
                       EXPO=data.expo, BETA=data.beta, SAFE=data.safe, FAC1=data.fac1,
                       FAC2=data.fac2, DENSE_NFEV=dense_nfev)
    shift = tup(f"y[{i}] + h * v[{i}]" for i in range(n))
    return (consts + f"\n{INLINE}\ndef to_tuple_shift(y, h, v):\n    return {shift}\n"
            + "\n".join(body) + "\n" + "".join(copy(fn, role) for fn, role in CONTROLLER)
            + dense)


def write_pair(data):
    """The writer of a pair's cell: its fixed step, and its adaptive part when ``adaptive``."""
    fixed = write_erk(data.tab)

    def write(ctx) -> str:
        text = fixed(ctx)
        if ctx.values.get("adaptive"):
            text += write_attempt(data, ctx)
        return text
    return write
