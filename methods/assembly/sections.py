"""Poincaré sections in a kernel module: Hénon's trick written out for the cell, and the parts a
section driver adds.

The templates are templates/events.py (the crossing test, the writer, the locators) and
templates/sampling.py (``section_rows``); this module writes what has to be unrolled for the cell's
dimension.

**Hénon's trick** (Hénon 1982, Physica D 5, 412-414), generated as tuple code for one cell.

To land on the section {g = 0} from a point (y, t) near it, integrate the augmented system in the
independent variable g:

    dy/dg = F(y) / (grad g . F(y)),   dt/dg = 1 / (grad g . F(y)),

from g(y) to 0 in one stretch Δg = -g(y). F is the field the cell integrates (its compiled ``f``:
the base field, or the modified one under +observer/+penalty, [B] (2.5), (2.10)); in a problem's
own module (external engines, transformed problems) it is the base field ``base_f``. The
integrator is DOP853's 8th-order solution (Hairer's coefficients, methods/dop853_coefficients.py)
with m equal substeps, m doubled from 2 until two successive results agree to HENON_RTOL
(|z_2m - z_m| <= HENON_RTOL max(1, |z_2m|) componentwise), at most HENON_MAX_SUBSTEPS. The located
point is on the exact flow of F through (t, y) up to that agreement. (choice) The substeps are
summed as the increment z - z0 with compensated (Kahan) summation: plain summation of z loses
about m/2 ulps, so near tangencies, where m must grow, the two results never agreed to 1e-15 and m
ran to the cap (measured: 11 of 7298 so(4) crossings at 4096 substeps, none with the compensated
sum, whose largest m is 1024).

The writer unrolls the 12 stages over the (N+1)-tuple (y, t), skipping zero coefficients, as
the explicit Runge-Kutta steps are written out (steps/erk.py), so a location allocates nothing.
For the dense-output locator it writes the value/slope pair that Newton on a continuous
extension solves for (templates/events.py ``dense_root``): g and grad g . du/dθ.
"""
from __future__ import annotations

import numpy as np
from gnibench.methods import dop853_coefficients as dop853
from gnibench.methods.assembly.source import ENTRY, INLINE, INTERNAL, constants, copy, tup
from gnibench.methods.assembly.templates import events, sampling
from gnibench.methods.tableau import weighted

HENON_RTOL = 1e-15            # agreement of the results with m and 2m substeps
HENON_MAX_SUBSTEPS = 4096
HENON_WALK_MAX = 256          # sub-intervals of the walk in time (16, 64, 256)
STAGES = dop853.N_STAGES      # DOP853's 12 stages; its 8th-order solution B over them


def event_constants() -> str:
    """The numbers the event templates read (templates/events.py), for a module's header."""
    return "".join(f"{k} = {getattr(events, k)!r}\n" for k in ("EPS", "DENSE_MAXIT", "SECANT_MAXIT"))


def _lincomb(z: str | None, h: str, terms, n1: int) -> str:
    """z + h (c0 v0 + ...) over the n+1 components (z None: a zero base, 0.0 + h (...)), written
    where it is used (not a helper function: see steps/erk.py ``lincomb``)."""
    return tup([f"{'0.0' if z is None else f'{z}[{i}]'} + {w}"
                for i, w in enumerate(weighted(h, terms, n1))])


def _run(name: str, rhs: str, n1: int) -> str:
    """``name(z0, d, m, par)``: m equal DOP853 substeps of dz = rhs(z) over d (unrolled)."""
    A = np.asarray(dop853.A, dtype=float)[:STAGES, :STAGES]
    B = np.asarray(dop853.B, dtype=float)
    zero = tup(["0.0"] * n1)
    run = [f"\n{INTERNAL}\ndef {name}(z0, d, m, par):",
           "    # m equal DOP853 substeps over d, accumulated as the increment dz = z - z0 by",
           "    # compensated (Kahan) summation: its rounding then neither acts on z nor grows with",
           "    # m, and results with m and 2m can agree to 1e-15",
           "    hs = d / m", f"    dz = {zero}", f"    cz = {zero}",
           "    for _ in range(m):", f"        z = {_lincomb('z0', '1.0', [(1.0, 'dz')], n1)}",
           f"        k0 = {rhs}(z, par)"]
    for i in range(1, STAGES):
        terms = [(A[i, j], f"k{j}") for j in range(i) if A[i, j] != 0.0]
        run.append(f"        k{i} = {rhs}({_lincomb('z', 'hs', terms, n1)}, par)")
    terms = [(B[j], f"k{j}") for j in range(STAGES) if B[j] != 0.0]
    run.append(f"        inc = {_lincomb(None, 'hs', terms, n1)}")
    run.append("        dz, cz = henon_kahan(dz, cz, inc)")
    run.append(f"    return {_lincomb('z0', '1.0', [(1.0, 'dz')], n1)}")
    return "\n".join(run) + "\n"


def henon_source(n: int, field: str = "f") -> str:
    """``henon_locate(y, t, t_next, par) -> (y*, t*, m, nfev, walked)`` for an n-dimensional state
    and section 0 of the problem, integrating the field named ``field`` (the logic is the template
    templates/events.py ``henon_locate``; here the unrolled parts)."""
    n1 = n + 1
    ys = tup([f"z[{i}]" for i in range(n)])
    dot = " + ".join(f"G[{i}] * F[{i}]" for i in range(n))
    helpers = [
        f"\n{INTERNAL}\ndef henon_rhs(z, par):",
        "    # (dy/dg, dt/dg) = (F, 1) / (grad g . F)  (Hénon 1982)",
        f"    y = {ys}", f"    F = {field}(y, par)", "    G = section_grad_0(y, par)",
        f"    d = {dot}",
        "    return " + tup([f"F[{i}] / d" for i in range(n)] + ["1.0 / d"]),
        f"\n{INTERNAL}\ndef flow_rhs(z, par):",
        "    # (dy/dt, dt/dt) = (F, 1): the same flow in time (to walk towards the section)",
        f"    F = {field}({ys}, par)",
        "    return " + tup([f"F[{i}]" for i in range(n)] + ["1.0"]),
        f"\n{INTERNAL}\ndef henon_slope(y, par):",
        "    # grad g . F = dg/dt along the flow",
        f"    F = {field}(y, par)", "    G = section_grad_0(y, par)", f"    return {dot}",
        f"\n{INLINE}\ndef henon_state(z):", f"    return {ys}",
        f"\n{INLINE}\ndef henon_join(y, t):",
        "    return " + tup([f"y[{i}]" for i in range(n)] + ["t"])]
    runs = _run("henon_run", "henon_rhs", n1) + _run("flow_run", "flow_rhs", n1)
    kahan = [f"\n{INLINE}\ndef henon_kahan(s, c, x):",
             "    # s + x with the running compensation c (Kahan summation)"]
    for i in range(n1):
        kahan += [f"    x{i} = x[{i}] - c[{i}]", f"    s{i} = s[{i}] + x{i}",
                  f"    c{i} = (s{i} - s[{i}]) - x{i}"]
    kahan.append("    return " + tup([f"s{i}" for i in range(n1)]) + ", "
                 + tup([f"c{i}" for i in range(n1)]))
    return (constants(HENON_RTOL=HENON_RTOL, HENON_MAX_SUBSTEPS=HENON_MAX_SUBSTEPS,
                      HENON_STAGES=float(STAGES), HENON_WALK_MAX=HENON_WALK_MAX)
            + "\n".join(kahan) + "\n"
            + "\n".join(helpers) + "\n" + runs
            + copy(events.henon_converge) + copy(events.henon_locate))


def locate_all_source() -> str:
    """``section_values`` (g at many samples) and ``henon_all`` (Hénon's trick from many samples)
    in one compiled call each (a problem's own module: the crossings of external engines and
    transformed problems, scanned after the run)."""
    return f'''
{ENTRY}
def section_values(Y, par, out):
    # g at every row of Y (the scan for crossings)
    for r in range(Y.shape[0]):
        out[r] = section_g_0(to_tuple(Y[r]), par)

{ENTRY}
def henon_all(T, Y, idx, par, out_t, out_y, out_ok, out_m):
    # from sample idx[j] (the one before crossing j): located point, direction, substeps
    for j in range(idx.shape[0]):
        ys, ts, m, _, _ = henon_locate(to_tuple(Y[idx[j]]), T[idx[j]], T[idx[j] + 1], par)
        out_t[j] = ts
        store(ys, out_y, j)
        out_ok[j] = section_cond_0(ys, par) > 0.0
        out_m[j] = m
'''


def section_parts(n: int, locator_from: str = "") -> str:
    """What a section driver calls: the crossing test, the writer, Hénon's locator and
    ``section_rows`` (a step's crossing by Hénon's trick). ``locator_from``: the name of a loaded
    module whose ``henon_locate`` integrates the same field (the problem's own module, for a cell
    whose field no modifier changes): the cell calls it instead of compiling a copy of its own
    (Hénon's locator was about half of a section cell's compilation)."""
    locator = henon_source(n) if not locator_from else (
        f"\nimport sys as _sys\n\nhenon_locate = _sys.modules[{locator_from!r}].henon_locate\n")
    return (copy(events.crosses, INLINE) + copy(events.section_event, INLINE)
            + copy(events.henon_crossing, INLINE) + locator + copy(sampling.section_rows, INLINE))


def dense_section_parts(n: int) -> str:
    """What the dense section driver calls: the crossing test, the writer, the crossing located
    on the step's continuous extension (``dense_crossing``, Newton on g along it) and
    ``section_rows``."""
    dot = " + ".join(f"G[{i}] * du[{i}]" for i in range(n))
    root = (f"\n{INLINE}\ndef root_value(u, par, tc, tk):\n    return section_g_0(u, par)\n"
            f"\n{INLINE}\ndef root_slope(u, du, par, tc):\n"
            f"    G = section_grad_0(u, par)\n    return {dot}\n")
    return (copy(events.crosses, INLINE) + copy(events.section_event, INLINE) + root
            + copy(events.dense_root) + copy(events.dense_crossing)
            + copy(sampling.section_rows, INLINE))
