"""Vector-field modifiers of [B] §2: the observer and the penalty method, simple and normalized.

observer  ξ' = F + D_Hᵀ (D_H D_Hᵀ)⁻¹ K (H0 − H)            [B] (2.5), K = diag(θ_i) [B] (2.6)
penalty   ξ' = F + D_Hᵀ K (H0 − H)                          [B] (2.10)

Normalized observer gains [B] §2: θ_i = α_i ‖D_Hᵀ (D_H D_Hᵀ)⁻¹ L(β)‖⁻¹, L(β) = diag(β). The matrix
norm is the Frobenius norm (the "Euclidean norm" of a matrix, [B] §2 "‖·‖ denotes the Euclidean
norm"); with G = D_H D_Hᵀ it is ‖·‖² = Σ_b β_b² (G⁻¹)_bb, computed without forming the N x q
matrix. (choice) Normalized penalty, which [B] names but does not write out: by analogy,
θ_i = α_i ‖D_Hᵀ L(β)‖⁻¹ = α_i (Σ_b β_b² ‖∇H_b‖²)^(-1/2).

Partial first integrals [B] (2.12)-(2.13) (observer only): a q-partial first integral H_p with
D_H F = L H_p, target Γ0 = {H_p = 0}. (reading) The OCR'd (2.13) writes the term as
D_Hᵀ (D_H D_Hᵀ)⁻¹ [K − L] H; with D_H F = L H that gives d/dt H = +K H (growth), and for L = 0 it is
not (PP) = (2.5) with H0 = 0, whose term is D_Hᵀ G⁻¹ K (H0 − H) = −D_Hᵀ G⁻¹ K H. The reading that
reduces to (2.5) and for which "the Main Lemma and its proof remain valid word for word" is

    ξ' = F + D_Hᵀ (D_H D_Hᵀ)⁻¹ [K (H0 − H) − L H],   H0 = 0,   so   d/dt H = L H − K H − L H = −K H.

Ordinary and partial integrals may be observed together (one G over all observed rows, L = 0 on
the rows of ordinary integrals): ``on=`` accepts both kinds of name; the canonical text lists the
partial ones under ``partial=``. An observed set of partial integrals must be closed under L
(L_ab = 0 for observed a, unobserved b), else it is not a q-partial first integral itself. The
Jacobian's leading term is then −D_Hᵀ G⁻¹ (K + L) D_H.

H0 is the value of the observed integrals at the initial point unless given. The term's code
(methods/assembly/steps/modifiers.py) is unrolled over the q observed integrals (q is small),
with the q x q system solved by Cholesky.
For implicit methods the Jacobian of the term is its leading part, −D_Hᵀ G⁻¹ K D_H (observer) or
−D_Hᵀ K D_H (penalty): the dropped terms are proportional to H0 − H, so Newton still converges to
round-off, since the residual it drives to zero is exact.
"""
from __future__ import annotations

from gnibench.methods.assembly.steps.modifiers import write_term
from gnibench.methods.base import Modifier
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.foundation.params import Param

_COMMON = (
    Param("mode", "simple", "simple: constant gains theta; normalized: gains from alpha, beta",
          kind="str", choices=("simple", "normalized")),
    Param("on", (), "observed integrals, first integrals or partial first integrals [B] (2.12) "
          "(default: all first integrals of the problem)", kind="names", show_default=False),
    Param("partial", None, "observed partial first integrals, target H = 0 ([B] (2.13); observer "
          "only; names given in on= are moved here)", kind="names"),
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
        from gnibench.problems.codegen import problem_meta

        meta = problem_meta(problem.record)
        names, pnames = meta["integrals"], meta.get("partial_integrals", [])
        for name in values.get("partial") or ():
            if name not in pnames:
                have = ", ".join(pnames) or "none"
                raise UserError(f"{kind}: partial={name} is not a partial first integral of "
                                f"{problem.id} (its partial first integrals: {have}); "
                                f"observe first integrals with on=")
        given = tuple(values["on"] or ()) + tuple(values.get("partial") or ())
        for name in given:
            if name not in names and name not in pnames:
                known = ", ".join(names + [f"{x} (partial)" for x in pnames])
                raise UserError(f"{kind}: problem {problem.id} has no integral {name!r}; "
                                f"its integrals: {known}")
        if len(set(given)) != len(given):
            raise UserError(f"{kind}: integral listed twice in on={'/'.join(given)}")
        on = tuple(x for x in given if x in names) if given else tuple(names)
        partial = tuple(x for x in given if x in pnames)
        if partial and kind != "observer":
            raise UserError(f"{kind}: {'/'.join(partial)} of {problem.id} are partial first "
                            "integrals; only the observer handles them ([B] (2.13))")
        out = dict(values, on=on)
        if "partial" in values:
            out["partial"] = partial or None
        q = len(on) + len(partial)
        order = [given.index(x) for x in on + partial] if given else list(range(q))
        if partial:
            _check_closed(meta, partial, kind)
        if kind in ("observer", "projection"):
            _check_independent(problem, names, on, kind, partial)
        for key in ("theta", "alpha", "beta", "H0"):
            v = out.get(key)
            if v is None:
                continue
            size = len(on) if key == "H0" else q
            if key == "H0" and not on:
                raise UserError(f"{kind}: H0 is for first integrals; the target of the partial "
                                f"integrals {'/'.join(partial)} is 0 ([B] (2.13))")
            if len(v) == 1:
                v = v * size
            if len(v) != size:
                what = "/".join(on if key == "H0" else given or on)
                raise UserError(f"{kind}: {key} has {len(out[key])} values for {size} observed "
                                f"integrals ({what}); allowed: 1 or {size} values")
            out[key] = tuple(v) if key == "H0" else tuple(v[i] for i in order)
        return out
    return resolve


def _check_closed(meta, partial, kind) -> None:
    """[B] (2.12) for the observed subset: D_H F = L H needs L_ab = 0 for unobserved b."""
    pn = meta["partial_integrals"]
    nz = meta["partial_L_nonzero"]
    for a in partial:
        for b, flag in zip(pn, nz[pn.index(a)]):
            if flag and b not in partial:
                raise UserError(f"{kind}: the derivative of {a} involves the partial integral {b} "
                                f"(L[{a},{b}] != 0, [B] (2.12)); observe {b} too")


def _check_independent(problem, names, on, kind, partial=()) -> None:
    """[B] §2 assumes rank D_H = q on Γ; refuse observed integrals that are dependent at y0."""
    import numpy as np
    from gnibench.problems.codegen import problem_meta, python_functions

    fns = python_functions(problem.record)
    y0 = problem.record.y0(problem.values)
    par = problem.record.par(problem.values)
    pn = problem_meta(problem.record).get("partial_integrals", [])
    rows = [fns[f"grad_{names.index(x)}"](y0, par) for x in on]
    rows += [fns[f"pgrad_{pn.index(x)}"](y0, par) for x in partial]
    D = np.array(rows, dtype=float)
    sv = np.linalg.svd(D, compute_uv=False)
    if not np.all(np.isfinite(sv)) or sv[0] == 0.0 or sv[-1] <= 1e-10 * sv[0]:
        observed = "/".join(tuple(on) + tuple(partial))
        raise UserError(
            f"{kind}: the integrals {observed} of {problem.id} are not functionally "
            f"independent at the initial point (rank D_H < {len(rows)}, [B] §2); "
            f"observe an independent subset with on=...")


def _observed(values):
    """(first integrals, partial first integrals) observed by a resolved modifier."""
    return tuple(values["on"]), tuple(values.get("partial") or ())


def _runtime(values, h0_at_start):
    """Numbers read from ``par``: H0 (one per observed first integral), then theta, or alpha
    and beta (one per observed integral, first integrals then partial ones)."""
    h0 = values["H0"] if values["H0"] is not None else tuple(h0_at_start)
    gains = values["theta"] if values["mode"] == "simple" else values["alpha"] + values["beta"]
    return tuple(float(x) for x in tuple(h0) + tuple(gains))


def _runtime_size(values):
    on, partial = _observed(values)
    q = len(on) + len(partial)
    return len(on) + (q if values["mode"] == "simple" else 2 * q)


def _modifier(kind, reference, doc):
    return Modifier(id=kind, reference=reference, doc=doc, params=_COMMON,
                    resolve=_resolve(kind), generate=write_term(kind), runtime=_runtime,
                    runtime_size=_runtime_size, needs_independent=(kind == "observer"))


observer = _modifier("observer", "[B] (2.5)-(2.6), normalized gains [B] §2, partial integrals (2.13)",
                     "observer: makes the level set of the observed integrals attracting")
penalty = _modifier("penalty", "[B] (2.10)", "penalty method: gradient pull towards the level set")
