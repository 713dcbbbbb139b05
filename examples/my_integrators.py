"""Python integrators for examples/definitions.toml (kind "python" and "python-solver")."""


def rk4_step(f, t, y, h):
    """One step of the classical Runge-Kutta method: f(t, y) -> y' (numpy arrays)."""
    k1 = f(t, y)
    k2 = f(t + h / 2, y + h / 2 * k1)
    k3 = f(t + h / 2, y + h / 2 * k2)
    k4 = f(t + h, y + h * k3)
    return y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)


def dop853_solve(f, y0, t_span, t_eval, rtol, atol):
    """A whole integration: the samples at t_eval, with scipy's own counts."""
    from scipy.integrate import solve_ivp

    r = solve_ivp(f, t_span, y0, method="DOP853", t_eval=t_eval, rtol=rtol, atol=atol)
    return {"y": r.y.T, "nfev": r.nfev, "status": "ok" if r.success else "error",
            "message": r.message}
