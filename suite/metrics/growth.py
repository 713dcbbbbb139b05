"""Growth of an error in time: envelope, exponent in t, secular drift and oscillation.

[HLW] Table 2.1 states how the errors of the Kepler problem grow with t: O(th) (explicit Euler's
energy, a linear drift), O(h) (symplectic Euler's energy, bounded, "no secular terms" [HLW] I.2.3),
O(t^2 h) (explicit Euler's global error). [B] §3 (end) and §7.2 (after Fig 29) describe an error
"oscillating around a stable non-zero value". The claims inventory (the claims inventory, Conventions) makes
these checkable:

* envelope(t) = max_{s <= t} |err(s)|;
* growth exponent in t = least-squares slope of log envelope against log t over a window;
* bounded / no drift: exponent <= 0.1 and max |err| over [T/2, T] <= 1.5 max |err| over [0, T/2]
  (thresholds proposed there; this metric gives the inputs, the claims ledger applies them).

The split of err(t) into a secular part and an oscillation is the least-squares line
err ≈ m + s t over the window: s is the drift (per unit time), half the peak-to-peak of the
residual the oscillation amplitude.
"""
from __future__ import annotations

import numpy as np
from gnibench.suite.foundation.params import Param
from gnibench.suite.metrics.base import Metric, MetricOutput, integral_names
from gnibench.suite.metrics.global_error import global_errors
from gnibench.suite.metrics.invariants import invariant_errors

GLOBAL = "global"
FIT_POINTS = 64           # log-spaced times at which the envelope enters the exponent fit
#: (choice) a growth exponent is fitted over samples spanning at least 0.8 of a decade of t (a
#: factor 6.3; a window of one decade, [T/10, T], sampled at whole periods from the fourth of 30
#: passes) and at least three samples; over less, a slope of log envelope against log t says
#: nothing about t^p (NaN, with the reason)
MIN_DECADES = 0.8
MIN_SAMPLES = 3


def envelope(err: np.ndarray) -> np.ndarray:
    """max_{s <= t} |err(s)| at every sample; NaN counts as infinite (a diverged error stays so)."""
    a = np.abs(np.asarray(err, dtype=float))
    return np.maximum.accumulate(np.where(np.isnan(a), np.inf, a)) if a.size else a


def growth_exponent(t: np.ndarray, env: np.ndarray, t_lo: float, t_hi: float,
                    points: int = FIT_POINTS) -> float:
    """Least-squares slope of log env against log t over [t_lo, t_hi] (the claims inventory, Conventions);
    NaN when the range is too short (:func:`growth_fit` says why)."""
    return growth_fit(t, env, t_lo, t_hi, points)[0]


def growth_fit(t: np.ndarray, env: np.ndarray, t_lo: float, t_hi: float,
               points: int = FIT_POINTS) -> tuple[float, str]:
    """The growth exponent over [t_lo, t_hi] and, when it is NaN, why.

    The fit uses the samples nearest below ``points`` log-spaced times in the window (each sample
    once), so every decade weighs the same however the samples are spaced. Samples with t <= 0 or
    env = 0 (nothing to take the log of) are left out; +inf when the envelope is infinite in the
    window (the error diverged); NaN when fewer than :data:`MIN_SAMPLES` usable samples remain or
    they span less than :data:`MIN_DECADES` decade of t.
    """
    t, env = np.asarray(t, dtype=float), np.asarray(env, dtype=float)
    t_lo = max(t_lo, float(np.min(t[t > 0]))) if np.any(t > 0) else t_lo
    if not (0 < t_lo < t_hi):
        return float("nan"), "no samples with t > 0 in the fit window"
    inside = (t >= t_lo) & (t <= t_hi)
    if np.any(np.isinf(env[inside])):
        return float("inf"), ""
    targets = np.geomspace(t_lo, t_hi, points)
    idx = np.unique(np.searchsorted(t, targets, side="right") - 1)
    idx = idx[(idx >= 0) & (t[idx] >= t_lo) & (env[idx] > 0) & np.isfinite(env[idx])]
    if len(idx) < MIN_SAMPLES:
        return float("nan"), (f"{len(idx)} usable samples in the fit window, {MIN_SAMPLES} "
                              f"needed")
    span = float(np.log10(t[idx[-1]] / t[idx[0]]))
    if span < MIN_DECADES:
        return float("nan"), (f"the samples span t = {t[idx[0]]:.3g} to {t[idx[-1]]:.3g}, "
                              f"{span:.2f} decades; at least {MIN_DECADES:g} needed")
    return float(np.polyfit(np.log(t[idx]), np.log(env[idx]), 1)[0]), ""


def drift_and_oscillation(t: np.ndarray, err: np.ndarray, t_lo: float,
                          t_hi: float) -> tuple[float, float, float]:
    """(drift s, mean of err, oscillation amplitude) over the window: err ≈ m + s t by least
    squares over the samples in [t_lo, t_hi]; the amplitude is half the peak-to-peak of the
    residual ([HLW] Table 2.1; [B] §3 "oscillating around a stable non-zero value"). NaN when the
    window holds fewer than two samples or a non-finite error."""
    t, err = np.asarray(t, dtype=float), np.asarray(err, dtype=float)
    inside = (t >= t_lo) & (t <= t_hi)
    tw, ew = t[inside], err[inside]
    if len(tw) < 2 or not np.all(np.isfinite(ew)) or np.ptp(tw) == 0:
        return float("nan"), float("nan"), float("nan")
    slope, offset = np.polyfit(tw, ew, 1)
    residual = ew - (offset + slope * tw)
    return float(slope), float(np.mean(ew)), float(np.ptp(residual) / 2)


def early_late_maxima(t: np.ndarray, err: np.ndarray) -> tuple[float, float, float]:
    """max |err| over [0, T/2] and over [T/2, T] (T = the last sample time), and their ratio
    late/early (the claims inventory "bounded / no drift": ratio <= 1.5). NaN counts as infinite; the ratio
    is 1 when both maxima are 0 (an exactly conserved quantity does not drift)."""
    t, a = np.asarray(t, dtype=float), np.abs(np.asarray(err, dtype=float))
    if not len(t):
        return float("nan"), float("nan"), float("nan")
    a = np.where(np.isnan(a), np.inf, a)
    half = t[-1] / 2
    early = float(np.max(a[t <= half], initial=0.0))
    late = float(np.max(a[t >= half], initial=0.0))
    if early == 0.0:
        ratio = 1.0 if late == 0.0 else float("inf")
    else:
        ratio = late / early
    return early, late, ratio


def errors_of(traj, names) -> dict[str, np.ndarray]:
    """The chosen errors of a trajectory, by name: err_<I> for an integral, the global error for
    ``global``; all of them (the global error when there is a reference) when ``names`` is None."""
    available = list(traj.integral_names) + ([GLOBAL] if traj.reference is not None else [])
    names = available if names is None else names
    out = {}
    for name in names:
        if name == GLOBAL:
            out[name] = global_errors(traj)
        else:
            out[name] = invariant_errors(traj)[:, traj.integral_names.index(name)]
    return out


def window_times(t: np.ndarray, window: tuple[float, float]) -> tuple[float, float]:
    """The window [a T, b T] in time, T = the last sample time."""
    t_final = float(t[-1]) if len(t) else float("nan")
    return window[0] * t_final, window[1] * t_final


def _compute(traj, problem, values) -> MetricOutput:
    out = MetricOutput()
    t_lo, t_hi = window_times(traj.t, values["window"])
    out.scalars["growth_window_start"], out.scalars["growth_window_end"] = t_lo, t_hi
    for name, err in errors_of(traj, values["of"]).items():
        env = envelope(err)
        out.columns[f"envelope_{name}"] = env
        drift, mean, amplitude = drift_and_oscillation(traj.t, err, t_lo, t_hi)
        early, late, ratio = early_late_maxima(traj.t, err)
        exponent, why = growth_fit(traj.t, env, t_lo, t_hi)
        out.scalars.update({
            f"growth_exponent_{name}": exponent, f"growth_reason_{name}": why,
            f"drift_{name}": drift, f"mean_err_{name}": mean, f"oscillation_{name}": amplitude,
            f"max_early_{name}": early, f"max_late_{name}": late,
            f"late_early_ratio_{name}": ratio})
    return out


def unknown_errors(problem, names) -> str:
    """Why ``names`` (integral names and ``global``) are not errors of the problem ("" if they
    are)."""
    if names is None:
        return ""
    allowed = list(integral_names(problem)) + [GLOBAL]
    bad = [n for n in names if n not in allowed]
    if bad:
        return (f"{problem.id} has no error {'/'.join(bad)}; allowed: {', '.join(allowed)} "
                "(global: needs a reference)")
    return ""


def _problem_check(problem, values) -> str:
    return unknown_errors(problem, values.get("of"))


def _check(traj, problem, values) -> str:
    names = values.get("of")
    if names is None and not traj.integral_names and traj.reference is None:
        return f"{problem.id} has no first integrals and the cell no reference"
    if names is not None and GLOBAL in names and traj.reference is None:
        return "of=global needs reference samples (no exact solution; use --reference)"
    if len(traj.t) < 3:
        return f"only {len(traj.t)} samples"
    return ""


def check_window(values) -> str:
    """The window option must be two fractions a/b with a < b."""
    w = values["window"]
    return "" if len(w) == 2 and w[0] < w[1] else f"bad window={'/'.join(map(str, w))}; " \
        "allowed: two fractions a/b of the final time with 0 <= a < b <= 1"


growth = Metric(
    id="growth", title="growth of an error in time: envelope, exponent in t, drift, oscillation",
    reference="[HLW] Table 2.1, I.2.3; [B] §3 (end), §7.2; the claims inventory Conventions",
    doc=("for each chosen error X (an integral's err_<I>, or the global error): the envelope "
         "max_{s<=t}|err_X(s)|; its growth exponent in t (least-squares log-log slope over the "
         "window, log-spaced samples); the least-squares line err_X = m + s t over the window "
         "(drift s) and half the peak-to-peak of the residual (oscillation); max|err_X| over "
         "[0, T/2] and [T/2, T] and their ratio (the claims inventory 'bounded / no drift': exponent <= 0.1 "
         "and ratio <= 1.5)"),
    compute=_compute, needs=("samples",),
    params=(Param("of", None, "the errors: integral names and/or global (default: every integral, "
                  "and global when there is a reference)", kind="names"),
            Param("window", (0.01, 1.0), "fit window [a T, b T] as fractions a/b of the last "
                  "sample time T", kind="floats", low=0.0, high=1.0)),
    columns=(("envelope_<X>", "max_{s<=t} |err_X(s)| (NaN counts as infinite)"),),
    scalars=(("growth_exponent_<X>", ("least-squares slope of log envelope vs log t over the window "
                                     "(inf: diverged; NaN: fewer than 3 samples or less than "
                                     "0.8 of a decade of t)")),
             ("growth_reason_<X>", "why growth_exponent_<X> is NaN (\"\" when it is not)"),
             ("drift_<X>", ("slope s of the least-squares line err_X = m + s t over the window, "
                           "per unit time")),
             ("mean_err_<X>", "mean of err_X over the window"),
             ("oscillation_<X>", "half the peak-to-peak of err_X - (m + s t) over the window"),
             ("max_early_<X>", "max |err_X| over [0, T/2]"),
             ("max_late_<X>", "max |err_X| over [T/2, T]"),
             ("late_early_ratio_<X>", "max_late / max_early (1 when both are 0)"),
             ("growth_window_start", "a T, start of the fit window"),
             ("growth_window_end", "b T, end of the fit window")),
    problem_check=_problem_check, check=_check, validate=check_window,
)
