"""The modifiers' code ([B] §2): the observer's and the penalty's terms, the projection's map.

The records, their options and the readings of [B] are methods/modifiers.py and
methods/projection.py; this module writes, unrolled over the q observed integrals, a field
modifier's ``mod<k>_term(y, par)`` (added to F, [B] (2.5), (2.10), (2.13)) and the leading part of
its Jacobian ``mod<k>_jac(y, par, J)``, or a step modifier's ``proj<k>(y, par)`` (applied to each
accepted step). How they join the field: :mod:`gnibench.methods.assembly.fields`.
"""
from __future__ import annotations

from gnibench.methods.assembly.source import INLINE, INTERNAL


def _observed(values):
    """(first integrals, partial first integrals) observed by a resolved modifier."""
    return tuple(values["on"]), tuple(values.get("partial") or ())


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
    """Common lines: gradients g_a, errors e_a = H0_a − H_a (−h_a for a partial integral, whose
    target is 0), gains th_a (and G, its factor). Observed rows: first integrals, then partial."""
    names = ctx.meta["integrals"]
    pnames = ctx.meta.get("partial_integrals", [])
    on, partial = _observed(values)
    idx = [names.index(x) for x in on]
    pidx = [pnames.index(x) for x in partial]
    qo, q, n = len(idx), len(idx) + len(pidx), ctx.n
    lines = [f"g{a} = grad_{k}(y, par)" for a, k in enumerate(idx)]
    lines += [f"g{qo + a} = pgrad_{k}(y, par)" for a, k in enumerate(pidx)]
    lines += [f"e{a} = par[{off + a}] - integral_{k}(y, par)" for a, k in enumerate(idx)]
    lines += [f"e{qo + a} = -partial_{k}(y, par)" for a, k in enumerate(pidx)]
    if kind == "observer":
        lines += [f"G{a}{b} = {_dot(f'g{a}', f'g{b}', n)}" for a in range(q) for b in range(a + 1)]
        lines += _cholesky(q)
    gain = off + qo
    if values["mode"] == "simple":
        lines += [f"th{a} = par[{gain + a}]" for a in range(q)]
    else:
        beta = [f"par[{gain + q + b}]" for b in range(q)]
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
        lines += [f"th{a} = par[{gain + a}] * inv_norm" for a in range(q)]
    # L of [B] (2.12) on the observed partial rows: lr{a}[j] = L_{a, j} (j: problem-level index)
    lines += [f"lr{qo + a} = pl_{k}(y, par)" for a, k in enumerate(pidx)]
    return lines, q, qo, pidx


def _lmat(qo, q, pidx):
    """Entries of the observed block of L as text, (a, b) -> expr, only for partial rows/columns."""
    return {(a, b): f"lr{a}[{pidx[b - qo]}]" for a in range(qo, q) for b in range(qo, q)}


def write_term(kind):
    """The writer of an observer's or a penalty's term ``mod<k>_term(y, par)`` and its Jacobian
    ``mod<k>_jac(y, par, J)`` (k: the modifier's place in the cell; off: where its numbers start in
    ``par``)."""
    def write(ctx, values, k, off):
        n = ctx.n
        pre, q, qo, pidx = _prelude(kind, ctx, values, off)
        L = _lmat(qo, q, pidx)
        # right-hand side of G x = K (H0 - H) - L H, [B] (2.5), (2.13) (reading in the docstring);
        # with e = -H on the partial rows, -L H = L e
        rhs = [f"th{a} * e{a}" + "".join(f" + {L[a, b]} * e{b}" for b in range(qo, q) if a >= qo)
               for a in range(q)]
        if kind == "observer":
            body = pre + _solve(q, rhs, [f"x{a}" for a in range(q)])
        else:
            body = pre + [f"x{a} = th{a} * e{a}" for a in range(q)]
        comps = ", ".join(" + ".join(f"x{a} * g{a}[{i}]" for a in range(q)) for i in range(n))
        ref = ("(2.5)" + (", (2.13)" if q > qo else "")) if kind == "observer" else "(2.10)"
        term = (f"\n{INLINE}\ndef mod{k}_term(y, par):\n    # {kind} [B] {ref}\n"
                + "".join(f"    {ln}\n" for ln in body)
                + f"    return ({comps}{',' if n == 1 else ''})\n")
        # Jacobian, leading term: -D_H^T W D_H with W = G^-1 (K + L) (observer) or K (penalty)
        jac = list(pre)
        if kind == "observer":
            for b in range(q):
                unit = ["1.0" if i == b else "0.0" for i in range(q)]
                jac += _solve(q, unit, [f"w{a}_{b}" for a in range(q)])
            for a in range(q):
                for b in range(q):
                    extra = "".join(f" + w{a}_{c} * {L[c, b]}" for c in range(qo, q) if b >= qo)
                    jac.append(f"c{a}_{b} = w{a}_{b} * th{b}{extra}")
            wsum = " + ".join(f"g{a}[i] * c{a}_{b} * g{b}[j]" for a in range(q) for b in range(q))
        else:
            wsum = " + ".join(f"g{a}[i] * th{a} * g{a}[j]" for a in range(q))
        jac += ["for i in range(N):", "    for j in range(N):", f"        J[i, j] -= {wsum}"]
        jacs = (f"\n{INLINE}\ndef mod{k}_jac(y, par, J):\n"
                + "".join(f"    {ln}\n" for ln in jac))
        return term + jacs
    return write


def write_projection(ctx, values, k, off):
    """``proj<k>(y, par)``: the orthogonal projection of methods/projection.py (HNW IV.4),
    unrolled over the observed integrals."""
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
    return (f"\n{INTERNAL}\ndef proj{k}(y, par):\n    # orthogonal projection, HNW IV.4\n"
            + "".join(f"    {ln}\n" for ln in lines))
