"""What a cached reference solution must satisfy, checked from its content when it is read.

The checksum beside a cached reference (:func:`gnibench.suite.foundation.cache.read_checked`)
catches damage, not a forgery: whoever can rewrite the ``.npz`` can rewrite its ``.sha256``. So
a reference is also checked against what can be re-derived cheaply from the problem alone:

1. **Form.** ``y`` has one finite row of the problem's dimension per grid time; the
   full-precision samples (long double, real128), when present, round to ``y``.
2. **Start.** At t = 0 the reference is the initial point: ``y[0] == y0`` exactly (the integrators
   start from it; measured: exact for every cached reference).
3. **First integrals.** Every first integral of the problem stays at its initial value along the
   samples within ``DRIFT`` relative to its magnitude (measured on the cached heyoka and IAS15
   references: at most 1e-14; ``DRIFT`` = 1e-9 leaves five orders of margin).
4. **The flow.** Over the first sample interval (from y0, which is known) and one chosen at
   random (a forger cannot know which), the problem's own vector field, integrated by RK4 with
   step doubling until two results agree to 1e-10, must carry ``y[k]`` to ``y[k+1]`` within
   ``FLOW`` (1e-8, relative to the state's size). An interval the check cannot resolve within
   ``MAX_STEPS`` steps (a long gap between samples, fast dynamics) is skipped: the check calls
   the compiled field from Python (about 1 µs a call) and must stay cheap beside a read.

What remains possible: a forgery that starts at y0, stays on every integral's level set to 1e-9,
and follows the flow to 1e-8 on the two intervals checked, i.e. one that changes only intervals
not drawn this time (each read draws again: a forgery of a fraction p of the intervals survives
a read with probability about 1 - p), that drifts from the true solution by less than 1e-8 per
interval (a time shift growing that slowly: over N samples it can reach ~N x 1e-8 at the end),
or that sits where the sample gaps are too long to check.
Against a determined forger with write access to the cache only a recomputation, or a key the
forger cannot read, would do. Problems whose flow is broken by an identification map
(``post_step``: the genus-2 geodesic) skip check 4.
"""
from __future__ import annotations

import random

import numpy as np

DRIFT = 1e-9            # allowed change of a first integral, relative to its magnitude
FLOW = 1e-8             # allowed gap between y[k+1] and the flow of y[k], relative to |y|
AGREE = 1e-10           # RK4 with n and 2n steps must agree to this, relative to |y|
MAX_STEPS = 1024        # RK4 steps over one interval at most (beyond: the interval is skipped)


def problem_ok(problem_bound, t: np.ndarray, y: np.ndarray, y_full=None,
               rng: random.Random | None = None) -> str:
    """"" when the reference ``y`` on ``t`` passes checks 1-4, else why it does not."""
    from gnibench.suite.cell.compiled import problem_kernel

    rec = problem_bound.record
    if y.ndim != 2 or y.shape != (len(t), rec.dim) or not np.all(np.isfinite(y)):
        return f"its samples are not {len(t)} finite states of dimension {rec.dim}"
    if y_full is not None and (y_full.shape != y.shape
                               or not np.array_equal(np.asarray(y_full, dtype=np.float64), y)):
        return "its full-precision samples do not round to its samples"
    y0 = np.array(rec.y0(problem_bound.values), dtype=np.float64)
    if t[0] == 0.0 and not np.array_equal(y[0], y0):
        return "it does not start at the initial point"
    pk = problem_kernel(problem_bound)
    why = _integrals(pk, y, y0)
    if why or rec.post_step is not None or len(t) < 2:
        return why
    return _flow(pk, t, y, rng or random.Random())


def _integrals(pk, y: np.ndarray, y0: np.ndarray) -> str:
    if not pk.integral_names:
        return ""
    values = pk.integrals(y)
    start = np.array(pk.at(y0))
    scale = np.maximum(np.abs(start), np.max(np.abs(values), axis=0))
    floor = 1e-3 * float(np.max(scale)) + 1e-13 * (1.0 + float(np.max(np.abs(y)))) ** 2
    drift = np.max(np.abs(values - start), axis=0)
    bad = np.flatnonzero(drift > DRIFT * np.maximum(scale, floor))
    if len(bad):
        k = int(bad[0])
        return (f"its first integral {pk.integral_names[k]} changes by {drift[k]:.3g} along it "
                f"(allowed: {DRIFT:g} of its size {scale[k]:.3g})")
    return ""


def _rk4(f, par, y: np.ndarray, dt: float, n: int) -> np.ndarray:
    """n classical RK4 steps of the problem's field from y over dt ([HLW] II.1, Table 1.2), in
    tuples (the compiled field takes and returns tuples: no array per stage)."""
    h = dt / n
    half, sixth = 0.5 * h, h / 6.0
    y = tuple(float(v) for v in y)
    for _ in range(n):
        k1 = f(y, par)
        k2 = f(tuple([a + half * b for a, b in zip(y, k1)]), par)
        k3 = f(tuple([a + half * b for a, b in zip(y, k2)]), par)
        k4 = f(tuple([a + h * b for a, b in zip(y, k3)]), par)
        y = tuple([a + sixth * (b + 2.0 * c + 2.0 * d + e)
                   for a, b, c, d, e in zip(y, k1, k2, k3, k4)])
    return np.array(y)


def _flow(pk, t: np.ndarray, y: np.ndarray, rng: random.Random) -> str:
    f = getattr(pk.kernel, "base_f", None)
    if f is None:
        return ""
    picks = sorted({0, rng.randrange(len(t) - 1)})
    for k in picks:
        dt = float(t[k + 1] - t[k])
        size = 1.0 + float(np.max(np.abs(y[k])))
        n, previous, last = 8, None, None
        while n <= MAX_STEPS:
            now = _rk4(f, pk.par, y[k], dt, n)
            if not np.all(np.isfinite(now)):
                break
            diff = None if previous is None else float(np.max(np.abs(now - previous)))
            if diff is not None and diff <= AGREE * size:
                gap = float(np.max(np.abs(now - y[k + 1])))
                if gap > FLOW * size:
                    return (f"its samples at t = {t[k]:.17g} and {t[k + 1]:.17g} are not joined "
                            f"by the problem's flow (off by {gap:.3g})")
                break
            asymptotic = diff is not None and last is not None and diff < last / 8   # h^4
            if asymptotic and n * (diff / (AGREE * size)) ** 0.25 > MAX_STEPS:     # too costly
                break
            previous, last, n = now, diff, 2 * n
    return ""
