"""``[[problem]]`` entries: a user's ODE and its first integrals, made a :class:`Problem` record.

Keys (docs: reference, "User definitions")::

    id, title, reference, notes        # id required; the others text
    states = ["q", "p"]                # names; a Hamiltonian problem lists its q's, then its p's
    q = ["q"], p = ["p"]               # optional, Hamiltonian only: which states are q's and p's
                                       # (p[i] the momentum of q[i]); then states in any order
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

import cmath
import json
import keyword
import math

from gnibench.problems.base import Model, Problem
from gnibench.suite.cell.user.entries import Entry
from gnibench.suite.cell.user.expressions import CONSTANTS, FUNCTIONS
from gnibench.suite.foundation.params import Param

KEYS = ("id", "title", "reference", "notes", "states", "q", "p", "hamiltonian", "rhs",
        "integrals", "parameters", "initial", "period", "exact", "partition")
RESERVED = set(FUNCTIONS) | set(CONSTANTS) | {"t"}


def build_problem(e: Entry, origin) -> Problem:
    """The Problem record of one entry (raises UserError naming the file, entry and key)."""
    import sympy as sp

    e.keys(KEYS)
    pid = e.ident()
    pairs = _pairs(e)
    states = e.names("states", required=pairs is None) or list(pairs[0] + pairs[1])
    params = e.table_of("parameters")
    for name in list(states) + list(params):
        if name in RESERVED or keyword.iskeyword(name):
            raise e.error("states" if name in states else "parameters",
                          f"the name {name!r} is reserved (t, {', '.join(CONSTANTS)}, the "
                          f"functions and Python's keywords)")
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
        qs, ps = canonical_names(e, states, pairs)
        canonical = (ps, qs)
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
        if pairs is not None:
            raise e.error("q", "the keys 'q' and 'p' name the canonical pairs of a Hamiltonian; "
                               "a right-hand side's blocks are its 'partition'")
        texts = {}
        partition = _partition(e, states)
    integrals = {}
    for name, text in e.table_of("integrals").items():
        if name in texts:
            raise e.error(f"integrals.{name}", "H is the Hamiltonian's own integral (added "
                                               "already)")
        if keyword.iskeyword(name):
            raise e.error("integrals", f"the name {name!r} is reserved (Python's keywords)")
        integrals[name] = e.expr(f"integrals.{name}", text, syms)
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
    check_definition(e, states, syms, params, values, init, integrals, period, exact)
    model = _model(states, list(params), e.table.get("hamiltonian"),
                   e.table.get("rhs"), {k: e.table_of("integrals")[k] for k in integrals})
    return Problem(
        id=pid, title=e.text("title", pid), reference=e.text("reference", f"user definition "
                                                                        f"({e.source})"),
        state=tuple(states),
        params=tuple(Param(n, v, "parameter (user definition)") for n, v in values.items()),
        model=model, initial=_numbers(init, list(params), states, pid), canonical=canonical,
        partition=partition, exact=None if exact is None else _exact(exact, list(params), states),
        period=None if period is None else _period(period, list(params), states, init, pid),
        time_scale=None if period is None else _time_scale(_period(period, list(params), states,
                                                                   init, pid)),
        notes=e.text("notes", "", one_line=False), origin=origin,
        definition=json.dumps({"source": e.source, "entry": e.table}, sort_keys=True, default=str))


def _pairs(e: Entry):
    """The keys ``q`` and ``p`` (both or neither): (q names, p names), or None."""
    if ("q" in e.table) != ("p" in e.table):
        raise e.error("q" if "p" in e.table else "p", "missing: give both 'q' and 'p' (the "
                                                       "canonical pairs, p[i] the momentum of q[i])")
    if "q" not in e.table:
        return None
    qs, ps = e.names("q"), e.names("p")
    if len(qs) != len(ps):
        raise e.error("p", f"{len(ps)} name(s) for {len(qs)} q's; allowed: one momentum per q")
    both = set(qs) & set(ps)
    if both:
        raise e.error("p", f"{sorted(both)[0]!r} is both a q and a p")
    return tuple(qs), tuple(ps)


def _momentum_like(name: str) -> bool:
    return name[:1] in "pP"


def _position_like(name: str, momenta) -> bool:
    """A name that reads as a q: q…/Q…, or a momentum's name without its p (px -> x)."""
    return name[:1] in "qQ" or any(name in (m[1:], m[1:].lstrip("_")) for m in momenta)


def canonical_names(e: Entry, states, pairs) -> tuple[tuple, tuple]:
    """(q names, p names) of a Hamiltonian entry: its keys ``q`` and ``p``, which must hold every
    state once, else the first half of ``states`` and the second. Without ``q``/``p``, a list
    that reads p-first (a first-half name p…/P… and a second-half name q…/Q… or that momentum's
    name without its p) is refused: taken as written it would integrate the time-reversed flow."""
    if pairs is not None:
        qs, ps = pairs
        if sorted(qs + ps) != sorted(states):
            raise e.error("q", f"q = {list(qs)} and p = {list(ps)} must hold every state of "
                               f"{list(states)} once")
        return qs, ps
    if len(states) % 2:
        raise e.error("states", "a Hamiltonian problem has an even number of states (q's, "
                                "then p's)")
    half = len(states) // 2
    first, second = states[:half], states[half:]
    momenta = [s for s in first if _momentum_like(s)]
    positions = [s for s in second if _position_like(s, momenta)]
    if momenta and positions:
        raise e.error("states", f"{list(states)} reads p-first ({momenta[0]!r} among the q's, "
                                f"{positions[0]!r} among the p's), which would run the "
                                f"time-reversed flow; list the q's first, or give q = [...] and "
                                f"p = [...]")
    return tuple(first), tuple(second)


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


def _numbers(exprs, params, states=(), pid: str = "?"):
    """``initial(values)``: the initial point at these parameter values; a UserError naming the
    state when an expression is not a finite real number there (sqrt of a negative, 1/0). The
    points are kept per parameter values: sympy's ``evalf`` runs once for a cell, not at each
    use of its initial point (parsing, compiling, tabling)."""
    from gnibench.suite.foundation.errors import UserError

    known: dict[tuple, tuple] = {}

    def initial(values):
        key = tuple(values[n] for n in params)
        if key not in known:
            if len(known) >= 256:
                known.clear()
            known[key] = evaluate(values)
        return known[key]

    def evaluate(values):
        subs = {n: values[n] for n in params}
        out = []
        for k, x in enumerate(exprs):
            try:
                v = complex(x.subs({s: subs[s.name] for s in x.free_symbols}).evalf(20))
            except (TypeError, ValueError, ZeroDivisionError, OverflowError):
                v = complex("nan")
            if v.imag != 0 or not math.isfinite(v.real):
                name = states[k] if k < len(states) else str(k)
                shown = "not a number" if cmath.isnan(v) else f"{v:g}"
                raise UserError(f"problem {pid}: the initial value {name} = {x} is {shown} for "
                                f"these options; allowed: options where it is a finite real number")
            out.append(v.real)
        return tuple(out)
    return initial


def _y0(values, states, init, params):
    base = _numbers(init, params, states)(values)
    return [values.get(f"{s}0") if values.get(f"{s}0") is not None else b
            for s, b in zip(states, base)]


def _period(expr, params, states, init, pid: str = "?"):
    from gnibench.suite.foundation.errors import UserError

    def period(values):
        subs = {**{n: values[n] for n in params},
                **{f"{s}0": v for s, v in zip(states, _y0(values, states, init, params))}}
        try:
            value = complex(expr.subs({s: subs[s.name] for s in expr.free_symbols}).evalf(20))
        except (TypeError, ValueError, ZeroDivisionError, OverflowError):
            value = complex("nan")
        if value.imag != 0 or not 0 < value.real < math.inf:
            shown = f"{value.real:g}" if value.imag == 0 else f"{value:g} (not real)"
            raise UserError(f"problem {pid}: its period {expr} is {shown} for these "
                            f"options; allowed: options where it is a finite number > 0")
        return value.real
    return period


def _time_scale(period):
    """The characteristic time of the defaults (as ``Problem.time_scale_of`` makes it from a
    period: T/2π to 2 digits), 1 where the period is not a finite number > 0 at these values
    (an unbound orbit can be integrated; only η needs its period, and refuses it)."""
    from gnibench.suite.foundation.errors import UserError

    def time_scale(values):
        try:
            return float(f"{period(values) / (2 * math.pi):.2g}")
        except UserError:
            return 1.0
    return time_scale


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


# -- checks on load: the integrals are integrals, the exact solution solves, the period is one --

def check_definition(e: Entry, states, syms, params, values, init, integrals, period,
                     exact) -> None:
    """Refuse, naming the key, what cannot hold at the entry's default point (parameters and
    initial values as given), in 30-digit arithmetic: an integral I whose derivative
    ∇I·f along the field is not 0 there (a first integral, even a partial one, is constant along
    the solution through that point); an exact solution that does not start at the initial point
    or does not solve y' = f(y) at t = 0, 0.3 and 1.1; a period that is not a finite number > 0.
    These are necessary conditions only: they catch a sign or a factor, not every error."""
    import sympy as sp

    at = {syms[n]: sp.nsimplify(v, rational=True) for n, v in values.items()}
    y0 = [sp.sympify(x).subs(at) for x in init]
    at.update({syms[s]: v for s, v in zip(states, y0)})
    f = _field(e, states, syms)
    grads = {name: [sp.diff(expr, syms[s]) for s in states] for name, expr in integrals.items()}
    for k, point in enumerate(_points(states, syms, at, y0)):
        fv = [x.evalf(30, subs=point) for x in f]
        for name, grad in grads.items():
            gv = [g.evalf(30, subs=point) for g in grad]
            rate = sum(g * x for g, x in zip(gv, fv))
            scale = sum(abs(g * x) for g, x in zip(gv, fv))
            if not _finite(scale):
                continue            # outside the domain (a start where f is not finite is
                                    # refused when a cell is made, with that reason)
            if not _small(rate, scale, 1e-15):
                where = "the initial point" if k == 0 else "a point near the initial one (" + \
                    ", ".join(f"{s}={float(sp.re(point[syms[s]])):.6g}" for s in states) + ")"
                raise e.error(f"integrals.{name}", f"not a first integral: d{name}/dt = "
                                                   f"∇{name}·f = {float(sp.re(rate)):.6g} ≠ 0 "
                                                   f"at {where}")
    y0_syms = {sp.Symbol(f"{s}0", real=True): v for s, v in zip(states, y0)}
    at0 = {**{k: v for k, v in at.items() if k.name in params}, **y0_syms}
    if period is not None:
        value = complex(sp.N(period.subs(at0), 20))
        if value.imag != 0 or not 0 < value.real < math.inf:
            raise e.error("period", f"{period} is {value.real:g} at the default point; allowed: "
                                    f"a finite number > 0")
    if exact is None:
        return
    tsym = sp.Symbol("t", real=True)
    for t in (0, sp.Rational(3, 10), sp.Rational(11, 10)):
        point = {**at0, tsym: t}
        x = [z.evalf(30, subs=point) for z in exact]
        dx = [sp.diff(z, tsym).evalf(30, subs=point) for z in exact]
        here = {**{k: v for k, v in at.items() if k.name in params},
                **{syms[s]: v for s, v in zip(states, x)}}
        fx = [z.evalf(30, subs=here) for z in f]
        for s, xi, yi, di, fi in zip(states, x, y0, dx, fx):
            if t == 0 and not _small(xi - yi, abs(yi) + 1, 1e-15):
                raise e.error(f"exact.{s}", f"starts at {float(sp.re(xi)):.17g}, not at the "
                                            f"initial value {float(sp.re(sp.N(yi))):.17g}")
            if not _small(di - fi, abs(di) + abs(fi), 1e-12):
                raise e.error(f"exact.{s}", f"does not solve the problem: d{s}/dt = "
                                            f"{float(sp.re(di)):.10g} but f_{s} = "
                                            f"{float(sp.re(fi)):.10g} at t = {float(t):g} (from "
                                            f"the default initial point)")


def _points(states, syms, at: dict, y0: list) -> list[dict]:
    """The initial point and three fixed points near it (each state moved by 0.05 to 0.25 of
    1 + its size): an integral of the user's must be constant along every solution."""
    import sympy as sp

    out = [at]
    for k in (1, 2, 3):
        moved = dict(at)
        for i, (s, v) in enumerate(zip(states, y0)):
            step = sp.Rational((7 * i + 5 * k) % 9 - 4, 16)      # -1/4 .. 1/4, fixed
            moved[syms[s]] = v + step * (1 + abs(sp.N(v, 20)))
        out.append(moved)
    return out


def _finite(x) -> bool:
    try:
        return math.isfinite(abs(complex(x)))
    except (TypeError, ValueError):
        return False


def _small(value, scale, rtol: float) -> bool:
    try:
        v, sc = complex(value), float(scale)
    except (TypeError, ValueError):
        return False
    return abs(v) <= rtol * sc + 1e-25 and math.isfinite(abs(v))


def _field(e: Entry, states, syms) -> list:
    """The vector field as sympy expressions of the states and parameters."""
    import sympy as sp

    if "hamiltonian" in e.table:
        H = e.expr("hamiltonian", e.table["hamiltonian"], syms)
        q, p = canonical_names(e, states, _pairs(e))
        deriv = {}
        for qi, pi in zip(q, p):                    # [HLW] (1.10): q' = H_p, p' = -H_q
            deriv[qi], deriv[pi] = sp.diff(H, syms[pi]), -sp.diff(H, syms[qi])
        return [deriv[s] for s in states]
    return [e.expr(f"rhs.{s}", e.table["rhs"][s], syms) for s in states]
