"""Small helpers shared by the test files (imported as ``support``; tests/ is on sys.path).

Registry-wide sweeps compile one kernel per (problem, method, modifier) cell, ~1-3 s each (tens of
seconds for the 36-dimensional outer solar system). By default a sweep therefore takes, per
method, the first few eligible problems in order of dimension; set ``GNIBENCH_TEST_FULL=1`` to run
every eligible combination.
"""
from __future__ import annotations

import functools
import os

import numpy as np
import pytest

FULL = os.environ.get("GNIBENCH_TEST_FULL", "") not in ("", "0")


def cap(pids, n: int, registry) -> list[str]:
    """The first n problem ids by (dimension, registry order), or all of them with FULL."""
    order = list(registry)
    ranked = sorted(pids, key=lambda pid: (registry[pid].dim, order.index(pid)))
    return ranked if FULL else ranked[:n]


def per_family(ids) -> list:
    """Method ids as pytest parameters: the first of each family (``Method.family``: explicit-rk,
    embedded-rk, extrapolation, implicit-rk, partitioned, composition, splitting,
    generating-function) in the test command, so that every step writer and driver of the kernel
    assembly is exercised there; the others marked ``slow`` (CI runs ``pytest -m slow`` once after
    the test command; all of them run with ``GNIBENCH_TEST_FULL=1``). A registry-wide test over
    every compiled method compiles a kernel module per method and output, the largest share of
    the cold test command."""
    from gnibench.methods import COMPILED

    seen: set[str] = set()
    out = []
    for mid in ids:
        family = getattr(COMPILED[mid], "family", None) or mid
        first = family not in seen
        seen.add(family)
        out.append(mid if first or FULL else pytest.param(mid, marks=pytest.mark.slow))
    return out


def takes(pid: str, method: str) -> bool:
    """Whether a method accepts a problem (its structure needs), the problem with its default
    options. Decided at collection from the problem bound without the check of its initial
    point: that check generates the problem's code from sympy, which both test processes did at
    once, for every problem, before their first test (3 s each, cold)."""
    from gnibench.problems import REGISTRY
    from gnibench.suite.cell.spec import prepare
    from gnibench.suite.foundation.errors import UserError
    from gnibench.suite.foundation.params import Bound, bind

    rec = REGISTRY[pid]
    try:
        prepare(Bound(rec, bind(rec.params, {}, f"problem {pid}")), method)
    except UserError:
        return False
    return True


@functools.cache
def base_module(spec: str):
    """(module, problem Bound, par) of a problem's generated code (its own compiled module)."""
    from gnibench.methods.assembly import assemble_problem
    from gnibench.suite.cell.spec import parse_problem

    prob = parse_problem(spec)
    mod = assemble_problem(prob)
    return mod, prob, np.array(prob.record.par(prob.values), dtype=np.float64)


def rate_scale(spec: str) -> float:
    """Spectral radius of dF/dy at the initial point: the fastest local rate of the problem."""
    mod, prob, par = base_module(spec)
    n = prob.record.dim
    J = np.empty((n, n))
    mod.base_jac(tuple(prob.record.y0(prob.values)), par, J)
    return float(np.max(np.abs(np.linalg.eigvals(J))))


def integrals_at_start(spec: str) -> tuple[float, ...]:
    """H_k(y0) for every integral of the problem."""
    mod, prob, par = base_module(spec)
    return tuple(float(x) for x in mod.invariants(tuple(prob.record.y0(prob.values)), par))


def gradient_at_start(spec: str, k: int) -> np.ndarray:
    mod, prob, par = base_module(spec)
    return np.array(getattr(mod, f"grad_{k}")(tuple(prob.record.y0(prob.values)), par))


def gradients(spec: str, k: int, ys) -> np.ndarray:
    """∇H_k at each row of ys."""
    mod, _, par = base_module(spec)
    grad = getattr(mod, f"grad_{k}")
    return np.array([grad(tuple(y), par) for y in ys])


def synthetic_trajectory(spec: str, t, y, *, exact_reference: bool = False, kind: str = "samples",
                         chart=None, provenance: dict | None = None, y0=None):
    """A Trajectory built from given samples (e.g. the exact solution, or a constructed one) for
    testing metrics against known answers: the problem's integrals are evaluated at the samples
    by the problem's own compiled functions, y0 is the first sample (or ``y0``), and with
    ``exact_reference`` the exact solution at the sample times is attached as the reference."""
    from gnibench.suite.cell.compiled import problem_kernel
    from gnibench.suite.cell.spec import parse_problem
    from gnibench.suite.cell.trajectory import ReferenceSamples, Trajectory
    from gnibench.suite.foundation.status import Status

    prob = parse_problem(spec)
    t = np.ascontiguousarray(t, dtype=float)
    y = np.ascontiguousarray(y, dtype=float)
    y0 = tuple(float(v) for v in (y[0] if y0 is None else y0))
    pk = problem_kernel(prob)
    reference = None
    if exact_reference:
        reference = ReferenceSamples(prob.record.exact(t, y0, prob.values), {"backend": "exact"})
    zeros = np.zeros(len(t))
    return Trajectory(
        problem=prob.text(), method="synthetic", state_names=prob.record.state, t=t, y=y,
        steps=np.arange(len(t)), nfev=zeros, njev=zeros, rejected=zeros,
        integral_names=pk.integral_names, integrals=pk.integrals(y), H0=pk.at(y0), y0=y0,
        status=Status.OK, kind=kind, chart=chart, reference=reference,
        provenance=dict(provenance or {}))


def section_oscillator(monkeypatch, oid: str):
    """The harmonic oscillator q' = p, p' = -q with the section {q = 0, p > 0}, registered for
    one test under the id ``oid`` (its own kernels): it rotates (q, p) rigidly, so its crossings
    are known in closed form."""
    import dataclasses

    from gnibench import problems
    from gnibench.problems.base import Section

    rec = dataclasses.replace(
        problems.REGISTRY["harmonic-oscillator"], id=oid,
        sections=(Section(name="q=0,p>0", g=lambda S: S.q, condition=lambda S: S.p,
                          coords=("p",)),))
    monkeypatch.setitem(problems.REGISTRY, oid, rec)
    return rec
def stored_cells(out) -> int:
    """The finished cells a results directory's store holds: the records of its segments
    (``parts/*.seg``, suite/runs/partfile.py; a record cut short not counted)."""
    from pathlib import Path

    from gnibench.suite.runs.partfile import scan

    total = 0
    for seg in (Path(out) / "parts").glob("*.seg"):
        with open(seg, "rb") as f:
            total += len(scan(f, seg.name)[0])
    return total


def three_executors(experiment, tmp_path) -> dict:
    """``gnibench run`` of an experiment file serially, on a 2-process pool and on a 2-worker
    Dask LocalCluster (a real one): {executor: its output directory}."""
    from gnibench.suite.cli.main import main

    outs = {}
    for name, args in {"serial": ["-j", "1"], "pool": ["-j", "2"],
                       "dask": ["--executor", "dask", "-j", "2"]}.items():
        outs[name] = tmp_path / name
        assert main(["run", str(experiment), "-o", str(outs[name]), *args, "--no-report"]) == 0, \
            name
    return outs
