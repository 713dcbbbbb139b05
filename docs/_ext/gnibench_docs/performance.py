"""The performance page: the newest saved benchmark runs, with their machine, date and commit.

The numbers come from benchmark output only, never from prose: the runs that ``pytest benchmarks
--benchmark-only`` and ``gnibench bench`` save in pytest-benchmark's layout
(:mod:`gnibench.suite.foundation.benchmarks`). The build reads, in this order, the storages named
by ``GNIBENCH_DOCS_BENCHMARKS`` (``:``-separated), ``.benchmarks/`` of the working directory and
of the repository (this machine's history, git-ignored) and ``benchmarks/results/`` (runs
committed with the code). For each machine it shows the newest run of each benchmark group.
"""
from __future__ import annotations

import os
from pathlib import Path

from .common import Tree, cell, code, table

INTRO = """# Performance

The tables below are benchmark output, read by the documentation build from the saved runs of
`pytest benchmarks --benchmark-only` and `gnibench bench`; each says on which machine, when and at
which commit it was measured. Times on a shared or loaded machine are noisy: compare the ratios
measured in one run (a kernel against the C loop beside it), not times across machines.
{doc}`/how-to/timing-regressions` says how to produce and compare them,
{doc}`/explanation/timings` what is timed.
"""


def storages(repo: Path) -> list[Path]:
    named = [Path(p) for p in os.environ.get("GNIBENCH_DOCS_BENCHMARKS", "").split(":") if p]
    out = []
    for p in named + [Path.cwd() / ".benchmarks", repo / ".benchmarks", repo / "benchmarks" / "results"]:
        if p.is_dir() and p.resolve() not in {q.resolve() for q in out}:
            out.append(p)
    return out


def newest_runs(storage: Path) -> list[tuple[str, Path, dict]]:
    """(machine, file, run) of the newest run of each (machine, benchmark group)."""
    from gnibench.suite.foundation.benchmarks import load_run, runs

    seen = {}
    for machine, path in runs(storage):
        try:
            doc = load_run(path)
        except (ValueError, TypeError, OSError):
            continue
        groups = {str(b.get("group") or "other") for b in doc["benchmarks"]}
        for g in groups:
            seen[(machine, g)] = (machine, path, doc)
    out, done = [], set()
    for machine, path, doc in seen.values():
        if path not in done:
            done.add(path)
            out.append((machine, path, doc))
    return out


def _seconds(x: float, unit: str) -> str:
    if x != x:
        return "–"
    if "step" in unit:
        for scale, name in ((1e-9, "ns"), (1e-6, "µs"), (1e-3, "ms")):
            if x < scale * 1000:
                return f"{x / scale:.3g} {name}"
    return f"{x:.3g} s"


def _ratio(name: str, medians: dict[str, float]) -> str:
    """A numba kernel's median over the C loop's of the same run (``gnibench bench``'s pairs)."""
    if not name.endswith(" numba"):
        return ""
    stem = name[: -len(" numba")]
    for c in (f"{stem} C -O3", f"{stem} C port"):
        if c in medians and medians[c] > 0:
            return f"{medians[name] / medians[c]:.2f}"
    return ""


def run_section(machine: str, path: Path, doc: dict, repo: Path) -> str:
    info = doc.get("machine_info") or {}
    commit = doc.get("commit_info") or {}
    where = ", ".join(str(x) for x in (info.get("node"), info.get("processor") or info.get("machine"),
                                        info.get("system"), "Python " + str(info.get("python_version", "?")))
                      if x)
    try:
        shown = path.resolve().relative_to(repo.resolve())
    except ValueError:
        shown = path.name
    out = [f"## {machine}: {str(doc.get('datetime', ''))[:19]}\n",
           f"Measured on {cell(where)} at commit {code(str(commit.get('id', ''))[:10])}"
           + (" (uncommitted changes)" if commit.get("dirty") else "") + f"; file {code(shown)}.\n"]
    medians = {str(b.get("name")): float((b.get("stats") or {}).get("median", float("nan")))
               for b in doc["benchmarks"]}
    rows = []
    for b in doc["benchmarks"]:
        stats, extra = b.get("stats") or {}, b.get("extra_info") or {}
        unit = str(extra.get("unit") or "s per round")
        rows.append([cell(b.get("group") or "other"), code(b.get("name")),
                     cell(_seconds(float(stats.get("median", float("nan"))), unit)),
                     cell(_seconds(float(stats.get("min", float("nan"))), unit)),
                     cell(unit), cell(_ratio(str(b.get("name")), medians))])
    out.append(table(["group", "benchmark", "median", "min", "unit", "median / C's"], rows))
    return "\n".join(out)


def _verdicts(counts: dict) -> str:
    return ", ".join(f"{n} {v}" for v, n in counts.items()) or "–"


def mutation_section(repo: Path) -> str:
    """The newest saved mutation campaign (``benchmarks/mutants-*.json``, written by
    ``gnibench verify --mutants``): its score, date, scale, and what killed each mutant."""
    import json

    files = sorted((repo / "benchmarks").glob("mutants-20*.json"))   # the catalog, not held-out sets
    docs = []
    for f in files:
        try:
            docs.append((str(json.loads(f.read_text(encoding="utf-8")).get("date", "")), f))
        except (ValueError, OSError):
            continue
    if not docs:
        return ""
    date, path = max(docs)
    doc = json.loads(path.read_text(encoding="utf-8"))
    from gnibench.reports.mutation import blind_spots

    known = blind_spots()
    rows = []
    for m in doc.get("mutants", []):
        by = ", ".join(m.get("claims") or []) or ", ".join(m.get("tests") or []) or m.get("crash", "")
        outcome = "killed" if m.get("killed") else "inconclusive" if m.get("inconclusive") else "survived"
        why = "" if m.get("killed") else m.get("blind_spot") or known.get(m.get("id"), "")
        rows.append([code(m.get("id")), cell(outcome), cell(by or why or m.get("inconclusive", "")),
                     cell(m.get("description", ""))])
    base = doc.get("baseline") or {}
    return (f"## The last saved mutation campaign: {date}\n\n"
            f"`gnibench verify --mutants` at the {doc.get('scale', '?')} scale, file "
            f"{code(path.relative_to(repo))}: **{doc.get('killed')} of {doc.get('total')} mutants "
            f"killed** (campaign {'complete' if doc.get('complete') else 'incomplete'}; the "
            f"unmutated baseline: {_verdicts(base.get('verdicts') or {})}, "
            f"{len(base.get('unexpected') or [])} unexpected). {{doc}}`/explanation/mutation-testing` "
            "says what this measures.\n\n"
            + table(["mutant", "outcome", "killed by", "the bug"], rows))


def _value(v) -> str:
    if isinstance(v, float):
        return f"{v:.3g}"
    return "–" if v is None else str(v)


def _met(value, goal) -> str:
    op, target = goal[0], float(goal[1])
    if not isinstance(value, (int, float)) or isinstance(value, bool):
        return "not measured"
    ok = value >= target if op == ">=" else value <= target
    return f"{value:.3g} ({'met' if ok else 'not met'}: goal {op} {target:g})"


def script_sections(repo: Path) -> list[str]:
    """The newest saved result of each benchmark script (``benchmarks/results/<script>-*.json``,
    written by the script's ``--json``, :func:`gnibench.suite.foundation.benchmarks.script_result`):
    its rows, each goal read against them, where, when and under which load."""
    import json

    newest: dict[str, tuple[str, Path, dict]] = {}
    for f in sorted((repo / "benchmarks" / "results").glob("*.json")):
        try:
            doc = json.loads(f.read_text(encoding="utf-8"))
        except (ValueError, OSError):
            continue
        if not isinstance(doc, dict) or "script" not in doc or "rows" not in doc:
            continue
        key = str(doc["script"])
        if key not in newest or str(doc.get("date", "")) >= newest[key][0]:
            newest[key] = (str(doc.get("date", "")), f, doc)
    out = []
    for script, (date, f, doc) in sorted(newest.items()):
        commit, machine, load = doc.get("commit") or {}, doc.get("machine") or {}, doc.get("load") or {}
        rows = doc["rows"]
        goals = doc.get("goals") or {}
        cols = [k for k in dict.fromkeys(k for r in rows for k in r) if k not in goals]
        # the first column (what the row is), then each goal read, then the other measures
        body = [[cell(_value(r.get(k))) for k in cols[:1]]
                + [cell(_met(r.get(g), goals[g])) for g in goals]
                + [cell(_value(r.get(k))) for k in cols[1:]] for r in rows]
        loads = ", ".join(f"{k} {v:.1f}" for k, v in load.items() if isinstance(v, (int, float)))
        out.append(
            f"## {code(script)}: {date[:19]}\n\n"
            f"`python benchmarks/{script}`, file {code(f.relative_to(repo))}; measured on "
            f"{cell(str(machine.get('node', '?')))} ({machine.get('cpus', '?')} CPUs, "
            f"{cell(str(machine.get('processor', '')))}) at commit {code(str(commit.get('id', ''))[:10])}"
            + (" (uncommitted changes)" if commit.get("dirty") else "")
            + (f", load average (1 min) {loads}" if loads else "") + ". "
            + " ".join(f"{code(g)}: {cell(goals[g][2])}." for g in goals if len(goals[g]) > 2)
            + "\n\n" + table(cols[:1] + list(goals) + cols[1:], body))
    return out


def page(repo: Path) -> str:
    out = [INTRO]
    found = False
    for storage in storages(repo):
        for machine, path, doc in newest_runs(storage):
            found = True
            out.append(run_section(machine, path, doc, repo))
    if not found:
        out.append("No saved benchmark run was found when this page was built. Run "
                   "`pytest benchmarks --benchmark-only` and `gnibench bench` in the repository, "
                   "then build the documentation again.\n")
    out += script_sections(repo)
    out.append(mutation_section(repo))
    return "\n".join(out)


def write(srcdir: Path, repo: Path) -> None:
    Tree(srcdir / "reference").write("performance.md", page(repo))

