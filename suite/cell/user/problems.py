"""``[[problem]]`` entries: a user's ODE and its first integrals, made a :class:`Problem` record.

Keys (README, "User definitions")::

    id, title, reference, notes        # id required; the others text
    states = ["q", "p"]                # names; a Hamiltonian problem lists its q's, then its p's
    hamiltonian = "p^2/2 - cos(q)"     # either this ...
    rhs = {x = "a*x - x*y", y = "..."} # ... or the right-hand side of every state
    integrals = {L = "..."}            # first integrals (H is added for a Hamiltonian problem)
    parameters = {a = 1.0}             # numbers; overridable in specs (id:a=2)
    initial = {q = 1.0, p = "sqrt(a)"} # every state: a number or an expression of the parameters
    period = "2*pi"                    # optional: of the parameters and initial values <state>0
    exact = {q = "...", p = "..."}     # optional: of t, the parameters and <state>0
    partition = [["x"], ["y"]]         # optional, right-hand sides only: blocks u, v

The expressions are parsed by :mod:`.expressions` (a safe subset) and compiled through the same
code generation as the shipped problems (:mod:`gnibench.problems.codegen`, keyed by the entry's
text).
"""
from __future__ import annotations

import json

from gnibench.problems.base import Model, Problem
from gnibench.suite.cell.user.entries import Entry
from gnibench.suite.cell.user.expressions import CONSTANTS, FUNCTIONS
from gnibench.suite.foundation.params import Param

KEYS = ("id", "title", "reference", "notes", "states", "hamiltonian", "rhs", "integrals",
        "parameters", "initial", "period", "exact", "partition")
RESERVED = set(FUNCTIONS) | set(CONSTANTS) | {"t"}


def build_problem(e: Entry, origin) -> Problem:
    """The Problem record of one entry (raises UserError naming the file, entry and key)."""
    import sympy as sp

    e.keys(KEYS)
    pid = e.ident()
    states = e.names("states")
    params = e.table_of("parameters")
    for name in list(states) + list(params):
        if name in RESERVED:
            raise e.error("states" if name in states else "parameters",
                          f"the name {name!r} is reserved (t, {', '.join(CONSTANTS)} and the "
                          f"functions)")
    for name in params:
        if name in states or name in {f"{s}0" for s in states}:
            raise e.error("parameters", f"the parameter {name!r} clashes with a state or an "
                                        f"initial value option <state>0")
    values = {name: float(e.constant(f"parameters.{name}", v)) for name, v in params.items()}
    syms = {n: sp.Symbol(n, real=True) for n in list(states) + list(params)}
    if ("hamiltonian" in e.table) == ("rhs" in e.table):
        raise e.error(None, "give exactly one of the keys 'hamiltonian' and 'rhs'")
    canonical = partition = None
    if "hamiltonian" in e.table:
        if len(states) % 2:
            raise e.error("states", "a Hamiltonian problem has an even number of states (q's, "
                                    "then p's)")
        half = len(states) // 2
        canonical = (tuple(states[half:]), tuple(states[:half]))
        hamiltonian = e.text("hamiltonian")
        e.expr("hamiltonian", hamiltonian, syms)
        texts = {"H": hamiltonian}
    else:
        rhs = e.table_of("rhs", required=True)
        if sorted(rhs) != sorted(states):
            raise e.error("rhs", f"needs one expression per state ({', '.join(states)}), has "
                                 f"{', '.join(rhs)}")
        for s, text in rhs.items():
            e.expr(f"rhs.{s}", text, syms)
        texts = {}
        partition = _partition(e, states)
    for name, text in e.table_of("integrals").items():
        if name in texts:
            raise e.error(f"integrals.{name}", "H is the Hamiltonian's own integral (added "
                                               "already)")
        e.expr(f"integrals.{name}", text, syms)
        texts[name] = text
    initial = e.table_of("initial", required=True)
    if sorted(initial) != sorted(states):
        raise e.error("initial", f"needs a value for every state ({', '.join(states)})")
    psyms = {n: syms[n] for n in params}
    init = [e.expr(f"initial.{s}", initial[s], psyms) for s in states]
    with_y0 = {**psyms, **{f"{s}0": sp.Symbol(f"{s}0", real=True) for s in states}}
    period = e.expr("period", e.table["period"], with_y0) if "period" in e.table else None
    exact = None
    if "exact" in e.table:
        table = e.table_of("exact")
        if sorted(table) != sorted(states):
            raise e.error("exact", f"needs an expression for every state ({', '.join(states)})")
        tsym = sp.Symbol("t", real=True)
        exact = [e.expr(f"exact.{s}", table[s], {**with_y0, "t": tsym}) for s in states]
    model = _model(states, list(params), e.table.get("hamiltonian"),
                   e.table.get("rhs"), {k: v for k, v in texts.items() if k != "H"})
    return Problem(
        id=pid, title=e.text("title", pid), reference=e.text("reference", f"user definition "
                                                                        f"({e.source})"),
        state=tuple(states),
        params=tuple(Param(n, v, "parameter (user definition)") for n, v in values.items()),
        model=model, initial=_numbers(init, list(params)), canonical=canonical,
        partition=partition, exact=None if exact is None else _exact(exact, list(params), states),
        period=None if period is None else _period(period, list(params), states, init),
        notes=e.text("notes", "", one_line=False), origin=origin,
        definition=json.dumps({"source": e.source, "entry": e.table}, sort_keys=True, default=str))


def _partition(e: Entry, states):
    value = e.table.get("partition")
    if value is None:
        return None
    ok = (isinstance(value, list) and len(value) == 2 and all(isinstance(b, list) for b in value)
          and sorted(x for b in value for x in b) == sorted(states) and all(value))
    if not ok:
        raise e.error("partition", f"bad value {value!r}; allowed: two non-empty lists of state "
                                   f"names that together hold every state once")
    return tuple(value[0]), tuple(value[1])


def _model(states, params, hamiltonian, rhs, integrals):
    """``model(S)``: the sympy model, parsed again with the code generator's symbols."""
    from gnibench.suite.cell.user.expressions import parse

    def model(S):
        names = {n: getattr(S, n) for n in list(states) + list(params)}
        ints = {k: parse(v, names) for k, v in integrals.items()}
        if hamiltonian is not None:
            return Model(integrals={"H": parse(hamiltonian, names), **ints},
                         hamiltonian=parse(hamiltonian, names))
        return Model(integrals=ints, rhs=tuple(parse(rhs[s], names) for s in states))

    return model


def _numbers(exprs, params):
    def initial(values):
        subs = {n: values[n] for n in params}
        return tuple(float(x.subs({s: subs[s.name] for s in x.free_symbols})) for x in exprs)
    return initial


def _y0(values, states, init, params):
    base = _numbers(init, params)(values)
    return [values.get(f"{s}0") if values.get(f"{s}0") is not None else b
            for s, b in zip(states, base)]


def _period(expr, params, states, init):
    def period(values):
        subs = {**{n: values[n] for n in params},
                **{f"{s}0": v for s, v in zip(states, _y0(values, states, init, params))}}
        return float(expr.subs({s: subs[s.name] for s in expr.free_symbols}))
    return period


def _exact(exprs, params, states):
    import numpy as np
    import sympy as sp

    args = [sp.Symbol("t", real=True)] + [sp.Symbol(n, real=True) for n in params] + \
        [sp.Symbol(f"{s}0", real=True) for s in states]
    fn = sp.lambdify(args, exprs, modules="numpy")

    def exact(t, y0, values):
        t = np.asarray(t, dtype=float)
        cols = fn(t, *[values[n] for n in params], *[float(x) for x in y0])
        return np.column_stack([np.broadcast_to(np.asarray(c, dtype=float), t.shape)
                                for c in cols])
    return exact
