"""Orthogonal projection onto the level set after every step: the modern competitor of the observer
(beyond the seeds; HNW GNI IV.4, Algorithm 4.2, "standard projection").

After a step gives ỹ, find y = ỹ + D_H(ỹ)ᵀ λ with H(y) = H0 for the chosen integrals, by simplified
Newton: D_H(ỹ) D_H(ỹ)ᵀ Δλ = H0 − H(y_k). The q x q system is solved by an unrolled Cholesky
factorisation (factored once per step). Iterations stop at round-off (as for Newton in
methods/kernels/newton.py); no convergence in ``maxit`` iterations is status ``newton_failed``.
"""
from __future__ import annotations

from gnibench.methods.base import Modifier
from gnibench.methods.modifiers import _cholesky, _dot, _resolve, _solve
from gnibench.suite.foundation.params import Param

_PARAMS = (
    Param("on", None, "integrals to project on (default: all of the problem's)", kind="names"),
    Param("H0", None, "target values (default: at the initial point)", kind="floats"),
    Param("maxit", 20, "maximum simplified-Newton iterations per step", kind="int", low=1,
          high=1000, show_default=False),
)


def _runtime(values, h0_at_start):
    h0 = values["H0"] if values["H0"] is not None else tuple(h0_at_start)
    return tuple(float(x) for x in h0)


def _generate(ctx, values, k, off):
    names = ctx.meta["integrals"]
    idx = [names.index(x) for x in values["on"]]
    q, n = len(idx), ctx.n
    lines = [f"g{a} = grad_{i}(y, par)" for a, i in enumerate(idx)]
    lines += [f"G{a}{b} = {_dot(f'g{a}', f'g{b}', n)}" for a in range(q) for b in range(a + 1)]
    lines += _cholesky(q)
    lines += [f"lam{a} = 0.0" for a in range(q)]
    lines += ["z = y", "scale = 1.0"]
    lines += [f"scale = max(scale, abs(y[{i}]))" for i in range(n)]
    lines += ["prev = np.inf", f"for it in range({int(values['maxit'])}):"]
    body = [f"r{a} = par[{off + a}] - integral_{i}(z, par)" for a, i in enumerate(idx)]
    body += _solve(q, [f"r{a}" for a in range(q)], [f"d{a}" for a in range(q)])
    body += [f"lam{a} += d{a}" for a in range(q)]
    comps = ", ".join(f"y[{i}] + " + " + ".join(f"lam{a} * g{a}[{i}]" for a in range(q))
                      for i in range(n))
    body.append(f"z = ({comps}{',' if n == 1 else ''})")
    step = " + ".join(f"abs(d{a}) * math.sqrt(G{a}{a})" for a in range(q))
    body += [f"dnorm = {step}", "if newton_done(dnorm, prev, scale):", "    return z, STATUS_OK",
             "prev = dnorm"]
    lines += [f"    {ln}" for ln in body]
    lines.append("return z, STATUS_NEWTON_FAILED")
    return (f"\n@njit(cache=True)\ndef proj{k}(y, par):\n    # orthogonal projection, HNW IV.4\n"
            + "".join(f"    {ln}\n" for ln in lines))


projection = Modifier(
    id="projection", reference="beyond the seeds: HNW GNI IV.4 (standard projection)",
    doc="orthogonal projection of each step onto the level set of the chosen integrals",
    params=_PARAMS, resolve=_resolve("projection"), generate=_generate, runtime=_runtime,
    runtime_size=lambda values: len(values["on"]), needs_independent=True, kind="step")
