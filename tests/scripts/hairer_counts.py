"""Step counts of Hairer's DOPRI5 / DOP853 through scipy's ``integrate.ode``, for one run.

Run by tests/methods/test_hairer_counts.py in an interpreter whose scipy wraps Hairer's Fortran codes
(scipy < 1.17; see that test). Plain Python and numpy only, so nothing of gnibench is involved:
the Kepler field is written out by hand.

usage: python hairer_counts.py '{"method": "dop853", "tol": 1e-10, "t_end": ..., "y0": [...],
                                 "options": {...}}'
prints {"scipy": version, "naccpt": .., "nrejct": .., "nstep": .., "nfev": ..} as JSON.
"""
import json
import sys

import scipy
from scipy.integrate import ode


def kepler(t, y):
    """[HLW] (2.2) in the order (p1, p2, q1, q2): p' = -q/|q|^3, q' = p."""
    p1, p2, q1, q2 = y
    r3 = (q1 * q1 + q2 * q2) ** 1.5
    return [-q1 / r3, -q2 / r3, p1, p2]


def main():
    a = json.loads(sys.argv[1])
    r = ode(kepler).set_integrator(a["method"], rtol=a["tol"], atol=a["tol"], nsteps=10**8,
                                   **a.get("options", {}))
    r.set_initial_value(a["y0"], 0.0)
    r.integrate(a["t_end"])
    if not r.successful():
        raise SystemExit(f"scipy ode({a['method']}) failed")
    iw = r._integrator.iwork          # Hairer's IWORK(17..20): NFCN, NSTEP, NACCPT, NREJCT
    print(json.dumps({"scipy": scipy.__version__, "nfev": int(iw[16]), "nstep": int(iw[17]),
                      "naccpt": int(iw[18]), "nrejct": int(iw[19])}))


if __name__ == "__main__":
    main()
