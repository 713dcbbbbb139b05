"""Mutation testing of the verification itself: does the ledger notice a broken integrator?

A catalog (``suite/mutants/catalog.toml``) lists small plausible bugs of the integrators and
metrics, each as a file of the package, a snippet of its text that occurs there exactly once, its
replacement, what it does and why it is plausible. For each mutant, :func:`run_mutants`

1. copies the installed package (the repository root is the package ``gnibench``) to
   ``<work>/<id>/gnibench`` and applies the mutant to the copy (refusing a snippet that is not
   found exactly once; a mutant's further edits ``more``, the same bug where its text is written
   twice, e.g. a plain step and its compensated twin ``step_sum``, likewise);
2. runs ``gnibench verify`` on the copy in a subprocess, with ``PYTHONPATH`` pointing at the copy
   (checked: the subprocess imports the copy, not the installed tree), its own kernel cache
   (``GNIBENCH_CACHE_DIR``, seeded by hard links with the generated kernels and problem code of
   the unmutated baseline run: both are keyed by the hash of their own full text, so a mutated
   template gets a new key and compiles, an untouched one loads; every cache write is a rename,
   so nothing the mutant writes reaches the seed; reference solutions are not seeded, since their
   key does not cover the code that computes them) and its own results directory;
3. runs the catalog's fast tests on the copy the same way, when the ledger did not already kill
   the mutant (the tests must pass on the baseline);
4. calls the mutant *killed* when a claim's verdict differs from its expected one (or is
   ``error``) where the unmutated baseline's did not, when a test fails, or when the ledger run
   itself fails (exit code other than 0 and 1, or the time limit: a hang is noticed too).

The unmutated baseline runs first, through the same path. The result, ``<out>/mutants.json``
(score, date, and per mutant the claims and tests that killed it; rewritten after every mutant,
so an interrupted campaign keeps what it measured, with ``complete`` false), is what the report's ledger page and
the documentation show; the survivors are the ledger's known blind spots (each catalog entry may say
why it survives, ``blind_spot``).
"""
from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
import time
from dataclasses import MISSING, asdict, dataclass, fields
from importlib import resources
from pathlib import Path

from gnibench.suite.foundation.errors import UserError

#: what is not part of the package when it is copied
IGNORE = shutil.ignore_patterns(".venv", ".git", "__pycache__", "results", ".benchmarks",
                                "*.egg-info", ".pytest_cache", "build", "dist")
#: cache subfolders keyed by the hash of their full content (safe to share with a mutant)
SEEDED = ("kernels", "problems")


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
    """The mutants and the settings (``tests``: the test files run against each mutant) of the
    shipped catalog, or of ``text`` (a file of held-out ``[[mutant]]`` entries, same schema)."""
    from gnibench.suite.foundation.tomlfile import load_toml

    doc = load_toml(catalog_text() if text is None else text, source)
    settings = {k: v for k, v in doc.items() if k != "mutant"}
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


def package_root() -> Path:
    """The package this module belongs to (suite/ledger/ two levels down): importing the
    package top would import the API, a floor above the ledger (tests/test_layout.py)."""
    return Path(__file__).resolve().parents[2]


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


def copy_package(dest: Path) -> Path:
    """A copy of the installed package at ``dest/gnibench`` (the import root is ``dest``)."""
    target = dest / "gnibench"
    shutil.copytree(package_root(), target, ignore=IGNORE)
    return target


def apply(mutant: Mutant, copy: Path) -> None:
    problem = check(mutant, copy)
    if problem:
        raise UserError(f"mutant {problem}; refusing to apply it")
    path = copy / mutant.file
    text = path.read_text(encoding="utf-8")
    for original, replacement in mutant.edits():
        text = text.replace(original, replacement)
    path.write_text(text, encoding="utf-8")


def _env(import_root: Path, cache: Path) -> dict:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(import_root)
    env["GNIBENCH_CACHE_DIR"] = str(cache)
    env.pop("PYTEST_ADDOPTS", None)
    # tests/methods/test_hairer_counts.py compares with Hairer's Fortran in a venv it makes once in the
    # user's cache (not keyed by content, so not seeded): point the copy at it, else every mutant
    # would build its own
    if "GNIBENCH_FORTRAN_SCIPY_PYTHON" not in env:
        from gnibench.suite.foundation.cache import cache_dir

        fortran = cache_dir() / "scipy-fortran" / "bin" / "python"
        if fortran.is_file():
            env["GNIBENCH_FORTRAN_SCIPY_PYTHON"] = str(fortran)
    return env


def _link_or_copy(src: str, dst: str) -> None:
    try:
        os.link(src, dst)
    except OSError:
        shutil.copy2(src, dst)


def _seed_cache(source: Path | None, cache: Path) -> None:
    """Seed a mutant's own cache with hard links to ``source``'s kernels and problem code. Safe:
    gnibench and numba write every cache file by writing a new file and renaming it over the
    old one (never in place), so a write in the mutant's cache never reaches ``source``."""
    cache.mkdir(parents=True, exist_ok=True)
    if source is None:
        return
    for sub in SEEDED:
        if (source / sub).is_dir() and not (cache / sub).exists():
            try:       # a shared cache may change while it is linked: a partial seed is fine,
                shutil.copytree(source / sub, cache / sub, copy_function=_link_or_copy,
                                ignore=shutil.ignore_patterns("*.tmp*", ".*"))
            except shutil.Error:                 # every entry is verified when it is read
                pass


def _imports_copy(import_root: Path, env: dict) -> None:
    """Refuse to go on unless a subprocess with ``env`` imports the copy (not the installed tree)."""
    out = subprocess.run([sys.executable, "-c", "import gnibench; print(gnibench.__file__)"],
                         check=False, env=env, cwd=import_root, capture_output=True, text=True, timeout=120)
    where = Path(out.stdout.strip() or "?").resolve()
    if import_root.resolve() not in where.parents:
        raise UserError(f"the subprocess imports gnibench from {where}, not from the copy in "
                        f"{import_root}: an editable install shadows PYTHONPATH")


def _verify(import_root: Path, env: dict, out: Path, scale: str, jobs: int, claims: list[str],
            timeout: float) -> tuple[int, list[dict], str]:
    cmd = [sys.executable, "-m", "gnibench.suite.cli.main", "verify", *claims, "--scale", scale,
           "-j", str(jobs), "-o", str(out), "--format", "json", "--no-report"]
    try:
        run = subprocess.run(cmd, check=False, env=env, cwd=import_root, capture_output=True, text=True,
                             timeout=timeout)
    except subprocess.TimeoutExpired:
        return -1, [], f"timed out after {timeout:.0f} s"
    try:
        rows = json.loads(run.stdout) if run.stdout.strip() else []
    except ValueError:
        rows = []
    return run.returncode, rows, run.stderr.strip().splitlines()[-1] if run.stderr.strip() else ""


def _tests(copy: Path, env: dict, tests: list[str], jobs: int, timeout: float) -> tuple[int, list[str]]:
    if not tests:
        return 0, []
    cmd = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-rf", "-x",
           "-m", "not slow", *(["-n", str(jobs)] if jobs > 1 else []), *tests]
    try:
        run = subprocess.run(cmd, check=False, env=env, cwd=copy, capture_output=True, text=True,
                             timeout=timeout)
    except subprocess.TimeoutExpired:
        return -1, [f"tests timed out after {timeout:.0f} s"]
    failed = re.findall(r"^(?:FAILED|ERROR) (\S+)", run.stdout, flags=re.MULTILINE)
    if run.returncode not in (0, 5) and not failed:
        failed = [f"pytest exited {run.returncode}"]
    return run.returncode, failed


def run_one(mutant: Mutant | None, work: Path, scale: str, jobs: int, claims: list[str],
            tests: list[str], seed: Path | None, timeout: float,
            baseline: dict | None = None) -> dict:
    """Run the ledger and the tests on a copy of the package with ``mutant`` applied (None: the
    unmutated baseline). With ``baseline``, the tests run only when the ledger did not already
    kill the mutant (they cost as much as the ledger). Returns the raw outcome (see
    :func:`judge_mutant`)."""
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
    _seed_cache(seed, cache)
    env = _env(home, cache)
    _imports_copy(home, env)
    code, rows, last = _verify(home, env, home / "out", scale, jobs, claims, timeout)
    raw = {"id": name, "exit": code, "rows": rows, "stderr": last, "tests_exit": None,
           "tests_failed": [], "tests_run": False, "cache": str(cache), "home": str(home)}
    if baseline is None or not judge_mutant(raw, baseline)["killed"]:
        raw["tests_exit"], raw["tests_failed"] = _tests(copy, env, tests, jobs, timeout)
        raw["tests_run"] = bool(tests)
    raw["seconds"] = round(time.perf_counter() - start, 1)
    return raw


def judge_mutant(raw: dict, baseline: dict) -> dict:
    """Killed by which claims (unexpected verdicts the baseline did not have, or errors), which
    tests, or the ledger run failing as a whole."""
    calm = {r["id"] for r in baseline["rows"] if not r.get("unexpected")}
    claims = [r["id"] for r in raw["rows"] if r.get("unexpected") and r["id"] in calm]
    crash = raw["exit"] not in (0, 1) or not raw["rows"]
    why = []
    if crash:
        why.append(f"verify exited {raw['exit']}" + (f": {raw['stderr']}" if raw["stderr"] else ""))
    return {"claims": claims, "tests": list(raw["tests_failed"]), "crash": "; ".join(why),
            "killed": bool(claims or raw["tests_failed"] or crash)}


def _document(scale: str, claims: list[str], tests: list[str], results: list[dict],
              baseline: dict, planned: int) -> dict:
    from gnibench.suite.foundation.provenance import versions

    killed = sum(r["killed"] for r in results)
    return {"scale": scale, "claims": claims, "tests": tests, "mutants": results,
            "killed": killed, "total": len(results), "planned": planned,
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
                claims: list[str] | None = None, tests: list[str] | None = None,
                keep: bool = False, timeout: float = 3600.0, log=print,
                baseline_seed: Path | None = None) -> dict:
    """The baseline, then every mutant; writes and returns ``out/mutants.json``. The baseline's
    own cache is seeded from ``baseline_seed`` (default: the user's kernel cache; the baseline
    runs the installed code unchanged), and then seeds every mutant's own cache."""
    problems = [p for p in (check(m) for m in mutants) if p]
    if len(mutants) != len({m.id for m in mutants}):
        raise UserError("mutants: a mutant is listed twice")
    if problems:
        raise UserError("; ".join(problems))
    _, settings = load_catalog()
    tests = list(settings.get("tests", [])) if tests is None else tests
    claims = claims or ["all"]
    out.mkdir(parents=True, exist_ok=True)
    work = out / "mutants"
    if baseline_seed is None:
        from gnibench.suite.foundation.cache import cache_dir

        baseline_seed = cache_dir()
    log(f"gnibench: mutants: baseline (unmutated copy), {scale} scale")
    base = run_one(None, work, scale, jobs, claims, tests, baseline_seed, timeout)
    if base["exit"] not in (0, 1) or not base["rows"]:
        raise UserError(f"the unmutated baseline failed ({base['stderr']}); see {base['home']}")
    if base["tests_failed"]:
        raise UserError(f"the catalog's tests fail on the unmutated baseline: "
                        f"{', '.join(base['tests_failed'][:5])}; see {base['home']}")
    noisy = sorted(r["id"] for r in base["rows"] if r.get("unexpected"))
    baseline = {"exit": base["exit"], "unexpected": noisy, "seconds": base["seconds"],
                "verdicts": {v: sum(r["verdict"] == v for r in base["rows"])
                             for v in dict.fromkeys(r["verdict"] for r in base["rows"])}}
    results = []
    for k, m in enumerate(mutants, start=1):
        raw = run_one(m, work, scale, jobs, claims, tests, Path(base["cache"]), timeout, base)
        verdict = judge_mutant(raw, base)
        row = {**asdict(m), **verdict, "seconds": raw["seconds"], "exit": raw["exit"],
               "tests_run": raw["tests_run"]}
        for key in ("original", "replacement", "more"):
            row.pop(key)
        results.append(row)
        by = ", ".join(verdict["claims"][:6] + verdict["tests"][:3]) or verdict["crash"]
        log(f"gnibench: mutants: [{k}/{len(mutants)}] {m.id}: "
            + (f"killed by {by}" if verdict["killed"] else "SURVIVED") + f" ({raw['seconds']} s)")
        if not keep:
            shutil.rmtree(raw["home"], ignore_errors=True)
        # written after every mutant: an interrupted campaign keeps what it measured
        _write(out, _document(scale, claims, tests, results, baseline, len(mutants)))
    doc = _document(scale, claims, tests, results, baseline, len(mutants))
    _write(out, doc)
    if not keep:
        shutil.rmtree(work, ignore_errors=True)
    return doc
