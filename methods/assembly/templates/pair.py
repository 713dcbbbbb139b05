"""The embedded pairs' part of the adaptive loop (templates): attempt and step-size controller.

The loop is templates/adaptive.py. The pair's attempt is written from its tableau
(methods/assembly/steps/pair.py): ``attempt`` returns y1, its carry, the scaled rms error and f(y1) when
the pair has it, ``attempt_stages`` the same by the same operations plus the stages (dense
output); under ``sum=compensated`` they add the increment h Σ b_i k_i to y with the carried
rounding error e (methods/summation.py). The verdict is err <= 1 (``attempt_outcome``).

The controller is Hairer's (DOPRI5/DOP853, HNW I §II.4): err = ||h Σ e_j k_j / sk||_rms with
sk_i = atol + rtol max(|y_i|, |y1_i|) (DOP853: its combined 3rd/5th-order estimate); accepted if
err <= 1. New step h / fac, fac = clip(err^EXPO / facold^BETA / SAFE, 1/FAC2, 1/FAC1) (BETA: the PI
stabilisation of DOPRI5, facold = max(err, 1e-4) of the last accepted step); after a rejection
h / min(1/FAC1, err^EXPO / SAFE), and the next accepted step not larger than the rejected one;
|h| <= hmax. Rejections before the first accepted step are not counted, as in Hairer's codes.
The first step is h0, or Hairer's HINIT heuristic (templates/adaptive.py ``first_step``).
"""
from __future__ import annotations

from gnibench.methods.assembly.templates.slots import (
    ACCEPT,
    REJECT,
    STATUS_OK,
)


def adaptive_ws():
    return 0


def controller_init(y, fy, par, h0, hmax, rtol, atol, t_end):
    """The first step and the f-evaluations so far; facold starts at 1e-4 (Hairer's)."""
    h, nfev = first_step(y, fy, par, h0, hmax, rtol, atol)
    return h, nfev, 1.0e-4


def controller_state(x):
    return x


def controller_clip(h, hmax):
    """|h| <= hmax holds already: the first step and every new step are capped."""
    return h


def controller_prepare(ws, facold, first, last, reject, hmax):
    """Nothing: the pair's attempt does not depend on the controller."""
    return


def attempt_outcome(ws, err):
    """(lines: none, f-evaluations of an attempt, verdict: accepted when err <= 1)."""
    return 0, STAGES_NEW, ACCEPT if err <= 1.0 else REJECT


def controller_accept(h, facold, err, reject, kc, ws, hmax):
    """Hairer's PI step-size control after an accepted step: (h_new, facold)."""
    fac = err ** EXPO / facold ** BETA
    fac = max(1.0 / FAC2, min(1.0 / FAC1, fac / SAFE))
    hnew = h / fac
    if abs(hnew) > hmax:
        hnew = hmax
    if reject:
        hnew = min(abs(hnew), abs(h))
    return hnew, max(err, 1.0e-4)


def controller_reject(h, facold, err, verdict, kc, ws, nacc):
    """After a rejected step: (h_new, facold, counted)."""
    return h / min(1.0 / FAC1, err ** EXPO / SAFE), facold, nacc >= 1


def dense_coeffs(y, h, par, fy):
    """The accepted step from y of size h (fy = f(y)), recomputed by the operations of the
    driver's attempt (so y1 is the driver's, bit for bit; sum=plain), and its continuous
    extension: (y1, (y0, F0, F1, ...))."""
    e = carry_zero(y) if COMPENSATED else 0.0
    y1, _, _, f1, ks = attempt_stages(y, e, fy, h, par, 0, 1.0, 1.0)
    if not FSAL:
        f1 = f(y1, par)
    return y1, dense_from_stages(y, y1, h, par, ks, f1)


def partial_step(y, e, fy, sigma, par, ws, k):
    """A partial step of an embedded pair: its own step of size sigma from y (+ e; fy = f(y)), the
    error estimate unused (time grid without dense output)."""
    y1 = attempt(y, e, fy, sigma, par, ws, 1.0, 1.0)[0]
    return y1, STAGES_NEW, 0.0, STATUS_OK
