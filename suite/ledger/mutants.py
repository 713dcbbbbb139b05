"""Mutation testing of the verification itself: does the project notice a broken integrator?

A catalog (``suite/mutants/catalog.toml``) lists small plausible bugs of the integrators, the
metrics and the code around them, each as a file of the package, a snippet of its text that
occurs there exactly once, its replacement, what it does and why it is plausible; a TOML file of
held-out ``[[mutant]]`` entries has the same schema. For each mutant, :func:`run_mutants`

1. copies the installed package (the repository root is the package ``gnibench``, tests
   included) to ``<work>/<id>/gnibench`` and applies the mutant to the copy (refusing a snippet
   that is not found exactly once; a mutant's further edits ``more``, the same bug where its text
   is written twice, e.g. a plain step and its compensated twin ``step_sum``, likewise);
2. gives the copy its own kernel cache (``GNIBENCH_CACHE_DIR``, seeded by hard links with the
   generated kernels and problem code of the unmutated baseline run: both are keyed by the hash of
   their own full text, so a mutated template gets a new key and compiles, an untouched one
   loads; every cache write is a rename, so nothing the mutant writes reaches the seed; reference
   solutions are not seeded, since their key does not cover the code that computes them) and its
   own results directory, and checks that a subprocess imports the copy;
3. runs the whole verification on the copy, in subprocesses, stopping at the first kill: the
   tests that import the mutated module itself (pytest ``-x``), the ledger (``gnibench
   verify``), then the other tests that can see the mutated file through the modules between,
   one pytest call per import distance, nearest first
   (:mod:`.importers`: the reverse import graph of the package and its test modules, computed
   from the source, never a hand-kept list; ``tests = "all"``: the complete test suite);
4. calls the mutant *killed* when a claim's verdict differs from its expected one (or is
   ``error``) where the unmutated baseline's did not, when a test fails that passed on the
   baseline, when the ledger run itself fails (exit code other than 0 and 1), or when a phase
   overruns its time limit, FACTOR times the baseline's time plus SLACK
   (:mod:`.mutant_runs`; an overrun where the campaign's cap cut that limit is inconclusive).

The unmutated baseline's ledger runs first, through the same path. A test that fails against a
mutant is run again on the baseline's copy: it kills only when it passes there (a test that fails
unmutated is left out of every later mutant's run and listed in the result). The tests' time
limits come from their measured durations (``tests/durations.json``; without it a test phase's
overrun is inconclusive). The result, ``<out>/mutants.json`` (score, date, commit,
and per mutant what killed it and the tests selected; rewritten after every mutant, so an
interrupted campaign keeps what it measured, with ``complete`` false), is what the report's ledger
page and the docs' page on mutation testing show; the survivors are the verification's known
blind spots (each catalog entry may say why it survives, ``blind_spot``).
"""
from __future__ import annotations

import json
import shutil
import subprocess
import time
from dataclasses import MISSING, asdict, dataclass, field, fields
from importlib import resources
from pathlib import Path

from gnibench.suite.foundation.errors import UserError
from gnibench.suite.ledger.mutant_copies import (copy_package, env_for, imports_copy, package_root,
                                                 seed_cache)
from gnibench.suite.ledger.mutant_runs import FACTOR, SLACK

@dataclass(frozen=True)
class Mutant:
    """One small plausible bug (see the module docstring)."""

    id: str
    file: str
    original: str
    replacement: str
    description: str
    plausible: str
    blind_spot: str = ""
    #: further (original, replacement) pairs in the same file, applied with the first: one bug
    #: whose text occurs in two places (a plain step and its compensated twin ``step_sum``)
    more: tuple = ()

    def edits(self) -> list[tuple[str, str]]:
        return [(self.original, self.replacement)] + [tuple(pair) for pair in self.more]


def catalog_text() -> str:
    return (resources.files("gnibench.suite") / "mutants" / "catalog.toml").read_text("utf-8")


_KEYS = {f.name for f in fields(Mutant)}
_REQUIRED = tuple(f.name for f in fields(Mutant) if f.default is MISSING)


def load_catalog(text: str | None = None, source: str = "mutant catalog") -> tuple[list[Mutant], dict]:
    """The mutants of the shipped catalog, or of ``text`` (a file of held-out ``[[mutant]]``
    entries, same schema), and the file's other settings (none are known: a top-level key other
    than ``mutant`` is refused, e.g. the hand-kept ``tests`` list of earlier catalogs, which the
    reverse import graph replaced)."""
    from gnibench.suite.foundation.tomlfile import load_toml

    doc = load_toml(catalog_text() if text is None else text, source)
    settings = {k: v for k, v in doc.items() if k != "mutant"}
    if settings:
        raise UserError(f"{source}: unknown top-level keys {sorted(settings)}; allowed: [[mutant]] "
                        f"entries (the tests run against a mutant are chosen by what imports its "
                        f"file: gnibench verify --mutants --mutant-tests auto|all|none)")
    mutants, seen = [], set()
    entries = doc.get("mutant", [])
    if not isinstance(entries, list):
        raise UserError(f"{source}: bad mutant; allowed: [[mutant]] entries")
    for entry in entries:
        if not isinstance(entry, dict):
            raise UserError(f"{source}: bad mutant {entry!r}; allowed: [[mutant]] tables")
        ident = entry.get("id", "?")
        bad = sorted(set(entry) - _KEYS)
        missing = [k for k in _REQUIRED if not isinstance(entry.get(k), str) or not entry[k]]
        if bad or missing:
            raise UserError(f"{source}: mutant {ident}: " + (f"unknown keys {bad}; " if bad else "")
                            + (f"missing {missing}; " if missing else "")
                            + f"allowed: {', '.join(sorted(_KEYS))}")
        if not all(isinstance(p, list) and len(p) == 2 for p in entry.get("more", [])):
            raise UserError(f"{source}: {ident}: more must list [original, "
                            f"replacement] pairs")
        m = Mutant(**{**entry, "more": tuple(tuple(p) for p in entry.get("more", []))})
        if m.id in seen:
            raise UserError(f"{source}: {m.id} is listed twice")
        seen.add(m.id)
        mutants.append(m)
    return mutants, settings


def check(mutant: Mutant, root: Path | None = None) -> str:
    """Why ``mutant`` cannot be applied to the package at ``root`` ("" when it can)."""
    base = (root or package_root()).resolve()
    path = base / mutant.file
    if base not in path.resolve().parents:
        return f"{mutant.id}: {mutant.file} is outside the package"
    if not path.is_file():
        return f"{mutant.id}: no file {mutant.file}"
    text = path.read_text(encoding="utf-8")
    for k, (original, replacement) in enumerate(mutant.edits()):
        which = "the snippet" if k == 0 else f"snippet {k + 1}"
        n = text.count(original)
        if n != 1:
            return f"{mutant.id}: {which} occurs {n} times in {mutant.file} (must be once)"
        if original == replacement:
            return f"{mutant.id}: the replacement of {which} equals it"
    return ""


def apply(mutant: Mutant, copy: Path) -> None:
    problem = check(mutant, copy)
    if problem:
        raise UserError(f"mutant {problem}; refusing to apply it")
    path = copy / mutant.file
    text = path.read_text(encoding="utf-8")
    for original, replacement in mutant.edits():
        text = text.replace(original, replacement)
    path.write_text(text, encoding="utf-8")


@dataclass
class Plan:
    """What a campaign runs against each mutant (see the module docstring)."""

    scale: str = "quick"
    jobs: int = 2
    claims: tuple = ("all",)
    #: "auto" (the tests that can see the mutated file), "all" (the complete test suite), or a
    #: list of test files (relative to the package root)
    tests: object = "auto"
    cap: float = 3600.0                         # no phase runs longer than this (seconds)
    ledger_seconds: float | None = None         # the baseline's, for the time limits
    durations: dict = field(default_factory=dict)      # test file -> seconds on the baseline
    deselect: tuple = ()                        # tests that fail on the baseline


def selection(plan: Plan, file: str | None, root: Path | None = None) -> tuple[list[str], dict]:
    """(test files to run against a mutant of ``file``, their import distance to it)."""
    from gnibench.suite.ledger import importers

    root = root or package_root()
    graph = importers.import_graph(str(root.resolve()))
    node = importers.module_of(file) if file else ""
    dist = importers.importers(graph, node) if node in graph else {}
    if not isinstance(plan.tests, str):
        chosen = list(plan.tests)
    elif plan.tests == "none":
        chosen = []
    elif plan.tests == "all" or file is None:
        chosen = importers.all_test_files(root)
    else:
        chosen = importers.tests_seeing(root, file)
    return sorted(chosen, key=lambda t: (dist.get(t, 99), t)), dist


def _phases(plan: Plan, tests: list[str], dist: dict):
    """(name, test files or None for the ledger) in the order they run: the nearest tests, the
    ledger, the farther tests."""
    from gnibench.suite.ledger.mutant_runs import tiers

    groups = tiers(tests, dist)
    first = groups[:1] if groups and dist.get(groups[0][0], 99) <= 1 else []
    return ([("tests (importers)", first[0])] if first else []) + [("ledger", None)] + \
        [(f"tests ({len(g)} files)", g) for g in groups[len(first):]]


def run_one(mutant: Mutant | None, work: Path, plan: Plan, seed: Path | None,
            baseline: dict | None = None) -> dict:
    """The verification on a copy of the package with ``mutant`` applied (None: the unmutated
    baseline, which runs every phase of its plan to the end). A mutant's run stops at the first
    phase that kills it. Returns the raw outcome (see :func:`judge_mutant`)."""
    from gnibench.suite.ledger import mutant_runs as R

    name = mutant.id if mutant else "baseline"
    home = work / name
    if home.exists():
        shutil.rmtree(home)
    home.mkdir(parents=True)
    start = time.perf_counter()
    copy = copy_package(home)
    if mutant:
        apply(mutant, copy)
    cache = home / "cache"
    seed_cache(seed, cache)
    env = env_for(home, cache)
    imports_copy(home, env)
    tests, dist = selection(plan, mutant.file if mutant else None)
    raw = {"id": name, "exit": None, "rows": [], "stderr": "", "tests_failed": [],
           "timeouts": [], "inconclusive": [], "phases": [], "tests_selected": len(tests),
           "cache": str(cache), "home": str(home), "ledger_seconds": None}
    for k, (phase, files) in enumerate(_phases(plan, tests, dist)):
        if phase == "ledger":
            lim, sure = R.limit(plan.ledger_seconds, plan.cap)
            res = R.run_ledger(home, env, home / "out", plan.scale, plan.jobs,
                               list(plan.claims), lim, sure)
            raw.update(exit=res.exit, rows=res.rows, stderr=res.stderr,
                       ledger_seconds=round(res.seconds, 1))
        else:
            lim, _ = R.limit(R.estimate(files, plan.durations, plan.jobs), plan.cap)
            # the tests' durations were measured elsewhere (tests/durations.json, another load,
            # kernels compiled or not): an overrun of their limit is inconclusive, never a kill
            sure = False
            res = _confirmed_tests(copy, env, files, plan, lim, sure, home / f"junit{k}.xml",
                                   baseline)
            if not res.timed_out:
                raw["tests_failed"] += res.failed
        if res.timed_out:
            raw["timeouts" if res.conclusive else "inconclusive"].append(
                f"{phase}: {res.stderr or res.failed[0]} (limit {lim:.0f} s)")
        raw["phases"].append({"phase": phase, "seconds": round(res.seconds, 1),
                              "files": len(files) if files else None})
        if baseline is not None and judge_mutant(raw, baseline)["killed"]:
            break
    raw["seconds"] = round(time.perf_counter() - start, 1)
    return raw


def _confirmed_tests(copy: Path, env: dict, files: list[str], plan: Plan, lim: float, sure: bool,
                     report: Path, baseline: dict | None):
    """A mutant's test phase whose failures are confirmed on the unmutated baseline copy: a test
    that fails there too is no kill; it is left out (``plan.deselect``, for every later mutant
    too) and the phase runs again (at most three times)."""
    from gnibench.suite.ledger import mutant_runs as R

    for _ in range(3):
        res = R.run_tests(copy, env, files, plan.jobs, lim, plan.deselect, stop_first=True,
                          report=report, conclusive=sure)
        if res.timed_out or not res.failed or baseline is None:
            return res
        home = Path(baseline["home"])
        check = R.run_tests(home / "gnibench", env_for(home, Path(baseline["cache"])), res.failed[:1],
                            1, lim, (), stop_first=True, report=home / "confirm.xml")
        if not check.failed and check.exit in (0, 5):
            return res                       # passes unmutated: the mutant killed it
        plan.deselect = tuple(dict.fromkeys(plan.deselect + tuple(res.failed[:1])))
    return res


def judge_mutant(raw: dict, baseline: dict) -> dict:
    """Killed by which claims (unexpected verdicts the baseline did not have, or errors), which
    tests, the ledger run failing as a whole, or a phase overrunning its time limit."""
    calm = {r["id"] for r in baseline["rows"] if not r.get("unexpected")}
    claims = [r["id"] for r in raw["rows"] if r.get("unexpected") and r["id"] in calm]
    ran = raw["exit"] is not None and not any(t.startswith("ledger") for t in
                                                raw["timeouts"] + raw["inconclusive"])
    crash = ran and (raw["exit"] not in (0, 1) or not raw["rows"])
    why = [f"verify exited {raw['exit']}" + (f": {raw['stderr']}" if raw["stderr"] else "")] \
        if crash else []
    return {"claims": claims, "tests": list(raw["tests_failed"]), "crash": "; ".join(why),
            "timeout": "; ".join(raw["timeouts"]), "inconclusive": "; ".join(raw["inconclusive"]),
            "killed": bool(claims or raw["tests_failed"] or crash or raw["timeouts"])}


def durations(root: Path | None = None) -> dict[str, float]:
    """Test file (relative to the package root) -> its measured duration in seconds, from
    ``tests/durations.json`` (pytest --store-durations; {} without it)."""
    path = (root or package_root()) / "tests" / "durations.json"
    try:
        raw = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return {f"tests/{k}": float(v) for k, v in raw.items()
            if isinstance(v, (int, float)) and not isinstance(v, bool)}


def _document(plan: Plan, results: list[dict], baseline: dict, planned: int) -> dict:
    from gnibench.suite.foundation.provenance import versions

    killed = sum(r["killed"] for r in results)
    return {"scale": plan.scale, "claims": list(plan.claims),
            "tests": plan.tests if isinstance(plan.tests, str) else list(plan.tests),
            "limits": {"factor": FACTOR, "slack_seconds": SLACK, "cap_seconds": plan.cap},
            "mutants": results, "killed": killed, "total": len(results), "planned": planned,
            "complete": len(results) == planned, "date": time.strftime("%Y-%m-%d"),
            "score": killed / len(results) if results else None, "baseline": baseline,
            "versions": versions(), "commit": _commit()}


def _commit() -> str | None:
    """The git commit of the package's source tree, when it is a checkout (what was mutated)."""
    try:
        out = subprocess.run(["git", "-C", str(package_root()), "rev-parse", "HEAD"], check=False,
                             capture_output=True, text=True, timeout=30)
    except (OSError, subprocess.SubprocessError):
        return None
    return out.stdout.strip() or None if out.returncode == 0 else None


def _write(out: Path, doc: dict) -> None:
    (out / "mutants.json").write_text(json.dumps(doc, indent=1, ensure_ascii=False) + "\n",
                                      encoding="utf-8")


def run_mutants(mutants: list[Mutant], out: Path, scale: str = "quick", jobs: int = 2,
                claims: list[str] | None = None, tests="auto", keep: bool = False,
                timeout: float = 3600.0, log=print, baseline_seed: Path | None = None) -> dict:
    """The baseline, then every mutant; writes and returns ``out/mutants.json``. ``tests``:
    "auto", "all", "none" or a list of test files (see :class:`Plan`); ``timeout``: the cap of
    every phase. The baseline's own cache is seeded from ``baseline_seed`` (default: the user's
    kernel cache; the baseline runs the installed code unchanged), and then seeds every mutant's
    own cache."""
    problems = [p for p in (check(m) for m in mutants) if p]
    if len(mutants) != len({m.id for m in mutants}):
        raise UserError("mutants: a mutant is listed twice")
    if problems:
        raise UserError("; ".join(problems))
    plan = Plan(scale, jobs, tuple(claims or ["all"]), tests, float(timeout))
    out.mkdir(parents=True, exist_ok=True)
    work = out / "mutants"
    if baseline_seed is None:
        from gnibench.suite.foundation.cache import cache_dir

        baseline_seed = cache_dir()
    # the baseline runs the ledger; a test that fails against a mutant is run again on the
    # baseline's copy (a kill only when it passes there); the tests' time limits come from their
    # measured durations (tests/durations.json)
    log(f"gnibench: mutants: baseline (unmutated copy), {scale} scale")
    base = run_one(None, work, Plan(scale, jobs, plan.claims, "none", plan.cap), baseline_seed)
    if base["exit"] not in (0, 1) or not base["rows"]:
        raise UserError(f"the unmutated baseline failed ({base['stderr']}); see {base['home']}")
    if base["timeouts"] or base["inconclusive"]:
        raise UserError(f"the unmutated baseline overran the cap of {timeout:.0f} s: "
                        f"{'; '.join(base['timeouts'] + base['inconclusive'])}")
    noisy = sorted(r["id"] for r in base["rows"] if r.get("unexpected"))
    plan.ledger_seconds, plan.durations = base["ledger_seconds"], durations()
    baseline = {"exit": base["exit"], "unexpected": noisy, "seconds": base["seconds"],
                "ledger_seconds": base["ledger_seconds"],
                "tests_seconds": round(sum(plan.durations.values()), 1), "tests_failing": [],
                "verdicts": {v: sum(r["verdict"] == v for r in base["rows"])
                             for v in dict.fromkeys(r["verdict"] for r in base["rows"])}}
    results = []
    for k, m in enumerate(mutants, start=1):
        raw = run_one(m, work, plan, Path(base["cache"]), base)
        verdict = judge_mutant(raw, base)
        row = {**asdict(m), **verdict, "seconds": raw["seconds"], "exit": raw["exit"],
               "phases": raw["phases"], "tests_selected": raw["tests_selected"]}
        for key in ("original", "replacement", "more"):
            row.pop(key)
        results.append(row)
        baseline["tests_failing"] = list(plan.deselect)
        by = ", ".join(verdict["claims"][:6] + verdict["tests"][:3]) or verdict["crash"] \
            or verdict["timeout"]
        log(f"gnibench: mutants: [{k}/{len(mutants)}] {m.id}: "
            + (f"killed by {by}" if verdict["killed"] else "SURVIVED")
            + (f" (inconclusive: {verdict['inconclusive']})" if verdict["inconclusive"] else "")
            + f" ({raw['seconds']} s)")
        if not keep:
            shutil.rmtree(raw["home"], ignore_errors=True)
        # written after every mutant: an interrupted campaign keeps what it measured
        _write(out, _document(plan, results, baseline, len(mutants)))
    doc = _document(plan, results, baseline, len(mutants))
    _write(out, doc)
    if not keep:
        shutil.rmtree(work, ignore_errors=True)
    return doc
