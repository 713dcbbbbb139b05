"""Position in the orbit: η(nT), the angle between q(0) and q(nT) after n whole periods.

[B] §5.2 (Fig 12) defines the error in the position in the orbit as

    η(nT) = arccos( q(0)·q(nT) / (|q(0)| |q(nT)|) ),  T the period, n an integer,

zero for the exact flow. It measures the phase error that an energy error causes through the
period (a = -μ/(2H), [B] §5.1: "accumulation of energy errors ... stimulates a rapid growth of the
errors of position along the orbit"). arccos loses half the digits near 0 (arccos(1 - δ) ≈ √(2δ)),
so η is computed as atan2(|q(0) × q(nT)|, q(0)·q(nT)), the same angle, accurate to round-off.

The signed phase (beside [B]'s η ∈ [0, π]) is the same angle counted positive when q(nT) is ahead
of q(0) in the direction of motion (about the initial angular momentum c0 = q(0) × p(0)), and
unwrapped from one whole period to the next, so it grows past π as the phase error accumulates;
η = |phase| wrapped to [0, π]. The unwrapping needs a sample at every whole period (a phase change
of less than π per period).

η is defined only at samples with t = nT (to ``rtol`` relative); elsewhere the column is NaN.
The samples at whole periods come from the sampling: ``dt_out = T``
(:func:`gnibench.suite.metrics.compute.sampling_needs`) or, at fixed step h = T/N, ``every = N``.
Under K-S ([B] (5.4), ``kepler-3d:ks=true``) the integration runs in the fictitious time s, in
which one revolution takes Δs = 2π √(a/μ) (1 for [B]'s orbit): a fixed step Δs/N with ``every =
N`` samples each revolution, at a time t(s) that is nT only up to the integration error, so those
samples count with a looser ``rtol`` (e.g. 1e-6; the gap "how η(nT) is sampled for K-S" of
the claims inventory).
"""
from __future__ import annotations

import numpy as np
from gnibench.suite.foundation.params import Param
from gnibench.suite.metrics.base import Metric, MetricOutput, max_abs
from gnibench.suite.metrics.growth import check_window, envelope, growth_exponent


def period_of(problem) -> float | None:
    """The period T of a parsed problem's solution, or None."""
    period = getattr(problem.record, "period", None)
    return None if period is None else float(period(problem.values))


def positions_and_momenta(traj, problem) -> tuple[np.ndarray, np.ndarray]:
    """q and p at every sample, shape (rows, d), from the problem's canonical names."""
    p_names, q_names = problem.record.canonical
    qi = [traj.state_names.index(n) for n in q_names]
    pi = [traj.state_names.index(n) for n in p_names]
    return traj.y[:, qi], traj.y[:, pi]


def whole_periods(t: np.ndarray, period: float, rtol: float) -> np.ndarray:
    """n where t = nT to ``rtol`` (relative to max(t, T)), else -1."""
    t = np.asarray(t, dtype=float)
    n = np.rint(t / period)
    at = np.abs(t - n * period) <= rtol * np.maximum(np.abs(t), period)
    return np.where(at & (n >= 0), n, -1).astype(np.int64)


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a × b for rows of 2- or 3-vectors; in the plane the z component, as a (rows, 1) array."""
    if a.shape[-1] == 2:
        return (a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0])[..., None]
    return np.cross(a, b)


def signed_angles(q0: np.ndarray, q: np.ndarray, c0: np.ndarray) -> np.ndarray:
    """Angle from q0 to each row of q, in (-π, π], positive about c0 ([B] §5.2 η = |angle|).

    atan2(±|q0 × q|, q0·q): accurate to round-off also near 0 and π, where arccos is not.
    """
    w = cross(np.broadcast_to(q0, q.shape), q)
    sign = np.where(w @ c0 >= 0, 1.0, -1.0)
    return np.arctan2(sign * np.linalg.norm(w, axis=1), q @ q0)


def eta(traj, problem, rtol: float = 1e-12) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(η, unwrapped signed phase, n) at every sample; η and the phase are NaN off the whole
    periods, where n is -1 ([B] §5.2)."""
    p_names, q_names = problem.record.canonical
    q, _ = positions_and_momenta(traj, problem)
    start = dict(zip(traj.state_names, np.asarray(traj.y0, dtype=float)))
    q0 = np.array([start[s] for s in q_names])
    c0 = cross(q0[None, :], np.array([start[s] for s in p_names])[None, :])[0]
    n = whole_periods(traj.t, period_of(problem), rtol)
    rows = np.flatnonzero(n >= 0)
    rows = rows[np.argsort(n[rows], kind="stable")]
    eta_col, phase = np.full(len(traj.t), np.nan), np.full(len(traj.t), np.nan)
    with np.errstate(invalid="ignore"):
        angles = signed_angles(q0, q[rows], c0)
    eta_col[rows] = np.abs(angles)
    finite = np.isfinite(angles)           # a diverged state stays NaN; the rest is unwrapped
    phase[rows[finite]] = np.unwrap(angles[finite])
    return eta_col, phase, n


def _compute(traj, problem, values) -> MetricOutput:
    period = period_of(problem)
    eta_col, phase, n = eta(traj, problem, values["rtol"])
    rows = np.flatnonzero(n >= 1)
    out = MetricOutput(columns={"eta": eta_col, "eta_phase": phase})
    nan = float("nan")
    s = {"eta_period": period, "eta_periods": int(n[rows].max()) if len(rows) else 0,
         "eta_final": nan, "eta_max": nan, "eta_phase_final": nan, "eta_phase_rate": nan,
         "eta_exponent": nan}
    if len(rows):
        last = rows[np.argmax(n[rows])]
        s["eta_final"], s["eta_phase_final"] = float(eta_col[last]), float(phase[last])
        s["eta_max"] = max_abs(eta_col[rows])
        at = np.flatnonzero(n >= 0)
        nn, ph = n[at].astype(float), phase[at]
        if len(at) >= 2 and np.all(np.isfinite(ph)):
            s["eta_phase_rate"] = float(np.polyfit(nn, ph, 1)[0])
        order = np.argsort(nn, kind="stable")
        t_per = nn[order] * period
        env = envelope(ph[order])
        lo, hi = values["window"]
        s["eta_exponent"] = growth_exponent(t_per, env, lo * t_per[-1], hi * t_per[-1])
    out.scalars.update(s)
    return out


def _problem_check(problem, values) -> str:
    canonical = problem.record.canonical
    if canonical is None or len(canonical[1]) not in (2, 3):
        d = 0 if canonical is None else len(canonical[1])
        return (f"η needs positions q in the plane or in space; {problem.id} has {d} position "
                "component(s)")
    return ""


def _check(traj, problem, values) -> str:
    period = period_of(problem)
    n = whole_periods(traj.t, period, values["rtol"])
    if not np.any(n >= 1):
        return (f"no sample at a whole period t = nT, n >= 1 (T = {period:.17g}, to rtol "
                f"{values['rtol']:g}); sample with dt_out = T, or at fixed step h = T/N with "
                "every = N")
    return ""


position_in_orbit = Metric(
    id="eta", title="position in the orbit η(nT): angle between q(0) and q(nT)",
    reference="[B] §5.2, Fig 12; §5.1",
    doc=("η(nT) = angle between q(0) and q(nT) at the samples at whole periods t = nT (atan2 of "
         "|q0 x q| and q0.q, [B] §5.2's arccos without its loss near 0); the signed, unwrapped "
         "phase (positive ahead, about c0 = q0 x p0); per cell the final and largest η, the phase "
         "drift per period and the growth exponent of |phase| in t"),
    compute=_compute, needs=("period", "samples"),
    params=(Param("rtol", 1e-12, "a sample is at a whole period when |t - nT| <= rtol max(t, T)",
                  low=0.0, low_open=True, high=1e-3),
            Param("window", (0.01, 1.0), "window [a nT, b nT] of the exponent fit, as fractions "
                  "a/b of the last whole period sampled", kind="floats", low=0.0, high=1.0)),
    columns=(("eta", "η(nT) in [0, π] at samples t = nT; NaN elsewhere"),
             ("eta_phase", ("signed angle from q(0) to q(nT), unwrapped over n (positive ahead "
                           "in the direction of motion); NaN off t = nT"))),
    scalars=(("eta_period", "the period T (from the initial point)"),
             ("eta_periods", "the last whole period n sampled"),
             ("eta_final", "η at the last whole period sampled"),
             ("eta_max", "max of η over the whole periods n >= 1 (NaN counts as infinite)"),
             ("eta_phase_final", "the unwrapped signed phase at the last whole period"),
             ("eta_phase_rate", ("least-squares slope of the signed phase against n, rad per "
                                "period")),
             ("eta_exponent", "growth exponent in t of max_{m<=n} |phase(mT)| over the window")),
    problem_check=_problem_check, check=_check, validate=check_window,
)
