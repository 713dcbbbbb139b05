"""Newton stopping rule shared by the implicit kernels (template)."""
from __future__ import annotations


def newton_done(dnorm, prev, scale):
    """True once the Newton increment reached round-off.

    Converged when ||dz|| <= 4 eps scale, or when the increment stopped decreasing at a level that
    can only be round-off (<= 1e-10 scale): Newton converges quadratically, so a non-decreasing
    increment after that point is the floating-point floor, not a stall.
    """
    done = dnorm >= prev and dnorm <= 1e-10 * scale
    if dnorm <= 8.881784197001252e-16 * scale:
        done = True
    return done
