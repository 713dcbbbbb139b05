"""gnibench plugins: the SSP-RK3 of Shu and Osher as a Python step, Ralston's 2nd-order tableau,
and the Morse oscillator."""
from __future__ import annotations


def ssprk3_step(f, t, y, h):
    """Shu & Osher (1988), J. Comput. Phys. 77, 439, (2.18): third-order strong-stability-
    preserving Runge-Kutta as three convex combinations of Euler steps."""
    y1 = y + h * f(t, y)
    y2 = 0.75 * y + 0.25 * (y1 + h * f(t + h, y1))
    return y / 3 + 2 / 3 * (y2 + h * f(t + h / 2, y2))


SSPRK3 = {"kind": "python", "entry": "gnibench_example_integrator:ssprk3_step", "order": 3,
          "title": "SSP-RK3 (Shu-Osher), a Python step from an installed package",
          "reference": "Shu & Osher, J. Comput. Phys. 77 (1988) 439, (2.18)"}

RALSTON2 = {"kind": "explicit-rk", "order": 2, "c": [0, "2/3"], "A": [[], ["2/3"]],
            "b": ["1/4", "3/4"], "title": "Ralston's second-order method",
            "reference": "Ralston, Math. Comp. 16 (1962) 431"}

MORSE = {"states": ["q", "p"], "hamiltonian": "p^2/2 + D*(1 - exp(-a*q))^2",
         "parameters": {"D": 1.0, "a": 1.0}, "initial": {"q": 0.5, "p": 0.0},
         "title": "Morse oscillator", "reference": "Morse, Phys. Rev. 34 (1929) 57"}
