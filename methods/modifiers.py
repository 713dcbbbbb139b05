"""Vector-field modifiers of [B] §2: the observer and the penalty method, simple and normalized.

observer  ξ' = F + D_Hᵀ (D_H D_Hᵀ)⁻¹ K (H0 − H)            [B] (2.5), K = diag(θ_i) [B] (2.6)
penalty   ξ' = F + D_Hᵀ K (H0 − H)                          [B] (2.10)

Normalized observer gains [B] §2: θ_i = α_i ‖D_Hᵀ (D_H D_Hᵀ)⁻¹ L(β)‖⁻¹, L(β) = diag(β). The matrix
norm is the Frobenius norm (the "Euclidean norm" of a matrix, [B] §2 "‖·‖ denotes the Euclidean
norm"); with G = D_H D_Hᵀ it is ‖·‖² = Σ_b β_b² (G⁻¹)_bb, computed without forming the N x q
matrix. (choice) Normalized penalty, which [B] names but does not write out: by analogy,
θ_i = α_i ‖D_Hᵀ L(β)‖⁻¹ = α_i (Σ_b β_b² ‖∇H_b‖²)^(-1/2).

H0 is the value of the observed integrals at the initial point unless given. The generated code is
unrolled over the q observed integrals (q is small), with the q x q system solved by Cholesky.
For implicit methods the Jacobian of the term is its leading part, −D_Hᵀ G⁻¹ K D_H (observer) or
−D_Hᵀ K D_H (penalty): the dropped terms are proportional to H0 − H, so Newton still converges to
round-off, since the residual it drives to zero is exact.
"""
from __future__ import annotations

from methods.base import Modifier
from suite.errors import UserError
from suite.params import Param

_COMMON = (
    Param("mode", "simple", "simple: constant gains theta; normalized: gains from alpha, beta",
          kind="str", choices=("simple", "normalized")),
    Param("on", None, "observed integrals (default: all of the problem's)", kind="names"),
    Param("theta", (1.0,), "gains θ_i (one value, or one per observed integral)", kind="floats",
          low=0.0, low_open=True, only_if=("mode", "simple")),
    Param("alpha", (1.0,), "normalized gains α_i", kind="floats", low=0.0, low_open=True,
          only_if=("mode", "normalized")),
    Param("beta", (1.0,), "normalization weights β_i", kind="floats", low=0.0, low_open=True,
          only_if=("mode", "normalized")),
    Param("H0", None, "target values of the observed integrals (default: at the initial point)",
          kind="floats"),
)


def _resolve(kind):
    def resolve(values, problem):
        from problems.codegen import problem_meta

        names = problem_meta(problem.record)["integrals"]
        on = values["on"] or tuple(names)
        for name in on:
            if name not in names:
                raise UserError(f"{kind}: problem {problem.id} has no integral {name!r}; "
                                f"its integrals: {', '.join(names)}")
        if len(set(on)) != len(on):
            raise UserError(f"{kind}: integral listed twice in on={'/'.join(on)}")
        out = dict(values, on=tuple(on))
        q = len(on)
        if kind in ("observer", "projection"):
            _check_independent(problem, names, on, kind)
        for key in ("theta", "alpha", "beta", "H0"):
            v = out.get(key)
            if v is None:
                continue
            if len(v) == 1:
                v = v * q
            if len(v) != q:
                raise UserError(f"{kind}: {key} has {len(out[key])} values for {q} observed "
                                f"integrals ({'/'.join(on)}); allowed: 1 or {q} values")
            out[key] = tuple(v)
        return out
    return resolve


def _check_independent(problem, names, on, kind) -> None:
    """[B] §2 assumes rank D_H = q on Γ; refuse observed integrals that are dependent at y0."""
    import numpy as np

    from problems.codegen import python_functions

    fns = python_functions(problem.record)
    y0 = problem.record.y0(problem.values)
    par = problem.record.par(problem.values)
    D = np.array([fns[f"grad_{names.index(x)}"](y0, par) for x in on], dtype=float)
    sv = np.linalg.svd(D, compute_uv=False)
    if not np.all(np.isfinite(sv)) or sv[0] == 0.0 or sv[-1] <= 1e-10 * sv[0]:
        raise UserError(
            f"{kind}: the integrals {'/'.join(on)} of {problem.id} are not functionally "
            f"independent at the initial point (rank D_H < {len(on)}, [B] §2); "
            f"observe an independent subset with on=...")


def _runtime(values, h0_at_start):
    """Numbers read from ``par``: H0 (q values), then theta, or alpha and beta."""
    h0 = values["H0"] if values["H0"] is not None else tuple(h0_at_start)
    gains = values["theta"] if values["mode"] == "simple" else values["alpha"] + values["beta"]
    return tuple(float(x) for x in h0 + gains)


def _runtime_size(values):
    q = len(values["on"])
    return q + (q if values["mode"] == "simple" else 2 * q)


def _dot(a, b, n):
    return " + ".join(f"{a}[{i}] * {b}[{i}]" for i in range(n))


def _cholesky(q):
    """Lines computing the Cholesky factor l_ij of G = (G_ij) (lower triangle, unrolled)."""
    lines = []
    for j in range(q):
        s = " - ".join([f"G{j}{j}"] + [f"l{j}{k} * l{j}{k}" for k in range(j)])
        lines.append(f"l{j}{j} = math.sqrt({s})")
        for i in range(j + 1, q):
            s = " - ".join([f"G{i}{j}"] + [f"l{i}{k} * l{j}{k}" for k in range(j)])
            lines.append(f"l{i}{j} = ({s}) / l{j}{j}")
    return lines


def _solve(q, rhs, out):
    """Lines solving G out = rhs with the Cholesky factor (forward, then back substitution)."""
    lines = []
    for i in range(q):
        s = " - ".join([rhs[i]] + [f"z{k} * l{i}{k}" for k in range(i)])
        lines.append(f"z{i} = ({s}) / l{i}{i}")
    for i in reversed(range(q)):
        s = " - ".join([f"z{i}"] + [f"{out[k]} * l{k}{i}" for k in range(i + 1, q)])
        lines.append(f"{out[i]} = ({s}) / l{i}{i}")
    return lines


def _prelude(kind, ctx, values, off):
    """Common lines: gradients g_a, errors e_a = H0_a − H_a, gains th_a (and G, its factor)."""
    names = ctx.meta["integrals"]
    idx = [names.index(x) for x in values["on"]]
    q, n = len(idx), ctx.n
    lines = [f"g{a} = grad_{k}(y, par)" for a, k in enumerate(idx)]
    lines += [f"e{a} = par[{off + a}] - integral_{k}(y, par)" for a, k in enumerate(idx)]
    if kind == "observer":
        lines += [f"G{a}{b} = {_dot(f'g{a}', f'g{b}', n)}" for a in range(q) for b in range(a + 1)]
        lines += _cholesky(q)
    if values["mode"] == "simple":
        lines += [f"th{a} = par[{off + q + a}]" for a in range(q)]
    else:
        beta = [f"par[{off + 2 * q + b}]" for b in range(q)]
        if kind == "observer":
            # (G^-1)_bb from G x = e_b; Frobenius norm of D_H^T G^-1 L(beta)   [B] §2
            for b in range(q):
                unit = ["1.0" if i == b else "0.0" for i in range(q)]
                lines += _solve(q, unit, [f"u{b}_{i}" for i in range(q)])
            norm2 = " + ".join(f"{beta[b]} * {beta[b]} * u{b}_{b}" for b in range(q))
        else:
            norm2 = " + ".join(f"{beta[b]} * {beta[b]} * ({_dot(f'g{b}', f'g{b}', n)})"
                               for b in range(q))
        lines.append(f"inv_norm = 1.0 / math.sqrt({norm2})")
        lines += [f"th{a} = par[{off + q + a}] * inv_norm" for a in range(q)]
    return lines, q


def _generate(kind):
    def generate(ctx, values, k, off):
        n = ctx.n
        pre, q = _prelude(kind, ctx, values, off)
        if kind == "observer":
            body = pre + _solve(q, [f"th{a} * e{a}" for a in range(q)], [f"x{a}" for a in range(q)])
        else:
            body = pre + [f"x{a} = th{a} * e{a}" for a in range(q)]
        comps = ", ".join(" + ".join(f"x{a} * g{a}[{i}]" for a in range(q)) for i in range(n))
        term = (f"\n@njit(cache=True)\ndef mod{k}_term(y, par):\n    # {kind} [B] "
                f"{'(2.5)' if kind == 'observer' else '(2.10)'}\n"
                + "".join(f"    {ln}\n" for ln in body)
                + f"    return ({comps}{',' if n == 1 else ''})\n")
        # Jacobian, leading term: -D_H^T W D_H with W = G^-1 K (observer) or K (penalty)
        jac = list(pre)
        if kind == "observer":
            for b in range(q):
                unit = ["1.0" if i == b else "0.0" for i in range(q)]
                jac += _solve(q, unit, [f"w{a}_{b}" for a in range(q)])
            wsum = " + ".join(f"g{a}[i] * w{a}_{b} * th{b} * g{b}[j]"
                              for a in range(q) for b in range(q))
        else:
            wsum = " + ".join(f"g{a}[i] * th{a} * g{a}[j]" for a in range(q))
        jac += ["for i in range(N):", "    for j in range(N):", f"        J[i, j] -= {wsum}"]
        jacs = (f"\n@njit(cache=True)\ndef mod{k}_jac(y, par, J):\n"
                + "".join(f"    {ln}\n" for ln in jac))
        return term + jacs
    return generate


def _modifier(kind, reference, doc):
    return Modifier(id=kind, reference=reference, doc=doc, params=_COMMON,
                    resolve=_resolve(kind), generate=_generate(kind), runtime=_runtime,
                    runtime_size=_runtime_size, needs_independent=(kind == "observer"))


observer = _modifier("observer", "[B] (2.5)-(2.6), normalized gains [B] §2",
                     "observer: makes the level set of the observed integrals attracting")
penalty = _modifier("penalty", "[B] (2.10)", "penalty method: gradient pull towards the level set")
