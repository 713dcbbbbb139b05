"""``gnibench bench`` results as benchmark history: saved per machine and commit in pytest-benchmark's
storage layout (:mod:`gnibench.suite.foundation.benchmarks`), compared with the last saved run.

Each timed row of :func:`gnibench.suite.runs.bench.bench` becomes one benchmark entry (``stats`` in
seconds per step; ``extra_info.unit`` says so): the numba kernels (compared by ``--compare``) and
the references they are measured against, the C loops and solve_ivp (saved for the history, not
compared: they time the machine, not gnibench). The startup row is the second fresh process of
``gnibench solve`` (seconds per process).
"""
from __future__ import annotations

from pathlib import Path

from gnibench.suite.foundation.benchmarks import compare, last_values, machine_id, save_run

GROUP = "gnibench bench"
DEFAULT_THRESHOLD = 1.3


def _entry(name: str, lo: float, med: float, unit: str, scale: float, reference: bool) -> dict:
    return {"name": name, "fullname": f"gnibench-bench::{name}", "group": GROUP,
            "stats": {"min": lo * scale, "median": med * scale, "rounds": None},
            "extra_info": {"unit": unit, "reference": reference}}


def bench_entries(rows: list[dict]) -> list[dict]:
    """pytest-benchmark-like entries of the rows of ``bench()``."""
    out = []
    for r in rows:
        if "startup" in r:
            second = r["startup"][-1]
            out.append(_entry("startup: gnibench solve, second fresh process",
                              second["process_seconds"], second["process_seconds"], "s/process",
                              1.0, False))
        elif r.get("adaptive"):
            m = r["method"]
            out.append(_entry(f"adaptive {m} numba", r["us_min"], r["us_median"], "s/step", 1e-6,
                              False))
            if "c_us_min" in r:
                out.append(_entry(f"adaptive {m} C port", r["c_us_min"], r["c_us_median"],
                                  "s/step", 1e-6, True))
            if "scipy_us_min" in r:
                out.append(_entry(f"adaptive {m} solve_ivp", r["scipy_us_min"], r["scipy_us_min"],
                                  "s/step", 1e-6, True))
        elif "ns_min" in r:
            out.append(_entry(f"fixed {r['method']} numba", r["ns_min"], r["ns_median"], "s/step",
                              1e-9, False))
            if "c_ns_min" in r:
                out.append(_entry(f"fixed {r['method']} C -O3", r["c_ns_min"], r["c_ns_median"],
                                  "s/step", 1e-9, True))
        elif "c_ns_min" in r:
            out.append(_entry(f"fixed {r['method']}", r["c_ns_min"], r["c_ns_median"], "s/step",
                              1e-9, True))
    return out


def save_and_compare(rows: list[dict], storage: Path, save: bool = True, against: bool = False,
                     threshold: float = DEFAULT_THRESHOLD, log=None) -> int:
    """Compare (``against``) the medians with the last saved run of this machine, then save (with
    ``save``); 1 when a gnibench benchmark is more than ``threshold`` times slower, else 0."""
    import sys

    log = sys.stdout if log is None else log
    entries = bench_entries(rows)
    status = 0
    if against:
        machine = machine_id()
        previous = last_values(storage, machine)
        current = {e["fullname"]: e["stats"]["median"] for e in entries
                   if not e["extra_info"]["reference"]}
        table = compare(current, previous, threshold)
        if not table:
            print(f"compare: no earlier run of machine {machine} in {storage}", file=log)
        else:
            print(f"compare with the last saved run of {machine} (median, slower than "
                  f"{threshold:g}x fails):", file=log)
            for row in table:
                flag = "SLOWER" if row["slower"] else "ok"
                print(f"  {row['name']:<62} {row['previous']:.3e} -> {row['current']:.3e}  "
                      f"x{row['ratio']:.2f}  {flag}  ({row['run']})", file=log)
            slower = [r for r in table if r["slower"]]
            if slower:
                print(f"compare: {len(slower)} benchmark(s) slower than {threshold:g}x", file=log)
                status = 1
    if save:
        path = save_run(storage, entries)
        print(f"saved: {path}", file=log)
    return status
