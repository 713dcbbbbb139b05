"""``gnibench verify [ID...|all] [--scale quick|paper] [-j N] [--list] [--format json] [-o DIR]``.

A shell on the library (:func:`gnibench.suite.api.verifying.check_claims`): it runs what the
chosen claims need (through the runner: parallel, resumable, one store in ``DIR``, by default
``results/seeds``, the same as ``gnibench reproduce``'s, so either reuses the cells the other
ran), judges each claim from the tables, writes ``DIR/ledger.parquet``, ``DIR/ledger.md`` and the
report site of ``DIR`` (``DIR/report``, figures and ledger together). This module prints the
verdict per claim with the measured number beside the seed's and exits with 1 when a verdict
differs from its ``expected`` one (a known failure that starts to pass, or the reverse), else 0.
"""
from __future__ import annotations

import json
import math
import sys

from gnibench.suite.foundation.errors import UserError


def verify_command(a) -> int:
    """``gnibench verify``: the arguments to :func:`gnibench.suite.api.verifying.check_claims`,
    its verdicts printed (text or JSON), the exit code."""
    from gnibench.suite.api.verifying import check_claims, check_scale
    from gnibench.suite.ledger.verify import select_claims

    check_scale(a.scale)
    if a.format not in ("text", "json"):
        raise UserError(f"bad --format {a.format!r}; allowed: text, json")
    if getattr(a, "mutants", None):
        return mutants_command(a)
    if a.list:
        return _list(select_claims(a.claims), a)
    ledger = check_claims(a.claims, scale=a.scale, output=a.output, jobs=a.jobs,
                          executor=a.executor, scheduler=a.scheduler, report=not a.no_report)
    _print(ledger, a.format)
    if ledger.report is not None:
        print(f"gnibench: verify: report {ledger.report}", file=sys.stderr)
    return _summary(ledger)


def _list(claims, a) -> int:
    """``--list``: the claims, as text or JSON; the options of a run do not apply."""
    given = [name for name, value in (("-o", a.output), ("-j", a.jobs), ("--scheduler", a.scheduler))
             if value is not None]
    given += ["--executor"] if a.executor != "local" else []
    given += ["--no-report"] if a.no_report else []
    if given:
        raise UserError(f"{', '.join(given)} {'does' if len(given) == 1 else 'do'} not apply "
                        f"with --list (nothing is run or written); allowed with --list: claim ids, --format")
    if a.format == "json":
        print(json.dumps([{"id": c.id, "kind": c.kind, "how": c.how,
                           "what": c.experiment or c.check, "expected": c.expected,
                           "citation": c.citation} for c in claims], indent=1))
        return 0
    for c in claims:
        print(f"{c.id:<24} {c.kind}  {c.how:<14} {c.experiment or c.check or '-':<22} "
              f"expected {c.expected}  {c.citation}")
    return 0


def _print(ledger, form: str) -> None:
    """The verdicts on stdout: one line per claim, or JSON."""
    verdicts = ledger.verdicts
    if form == "json":
        rows = [{"id": v.id, "citation": v.citation, "verdict": v.verdict,
                 "expected": v.expected, "outcome": v.outcome, "unexpected": v.unexpected,
                 "measured": _jsonable(v.measured), "seed_value": v.seed_value,
                 "threshold": v.threshold, "figure": v.figure, "detail": v.detail,
                 "values": v.values,
                 "not_measured": v.not_measured, "runs": [r.describe() for r in v.runs]}
                for v in verdicts]
        print(json.dumps(rows, indent=1))
        return
    for v in verdicts:
        flag = f"  UNEXPECTED (expected {v.expected})" if v.unexpected else ""
        measured = v.row()["measured_text"]
        print(f"{v.id:<24} {v.verdict:<15} measured {measured or '-':<14} seed: "
              f"{v.seed_value or '-'}{'  [' + v.figure + ']' if v.figure else ''}{flag}")
        if v.verdict == "error":                  # why: the entry to fix
            print(f"{'':<24} {v.detail}")


def _summary(ledger) -> int:
    """The counts per verdict on stderr; exit 1 when a verdict differs from its expected one."""
    from gnibench.suite.ledger.verdicts import VERDICT_ORDER

    verdicts = ledger.verdicts
    counts = {k: sum(v.verdict == k for v in verdicts) for k in VERDICT_ORDER}
    print(f"gnibench: verify: {len(verdicts)} claims: "
          + ", ".join(f"{n} {k}" for k, n in counts.items())
          + f"; {len(ledger.unexpected)} differ from the expected verdict or failed to measure "
          f"(the expected verdicts are a regression record, not evidence); ledger in "
          f"{ledger.output}", file=sys.stderr)
    return 1 if ledger.unexpected else 0


def mutants_command(a) -> int:
    """``gnibench verify [ID...] --mutants [M1,M2,...|FILE.toml] [--mutant-tests auto|all|none]
    [--mutant-timeout S]``: mutation testing of the verification
    (:mod:`gnibench.suite.ledger.mutants`): the baseline and each mutant on a copy of the package,
    each checked by the ledger and the tests that can see the mutated file; prints which claims
    or tests killed each mutant, writes ``DIR/mutants.json`` (default DIR:
    results/seeds, beside the ledger, so that its report page shows the score), exit 0 when every
    mutant was killed, 1 when some survived."""
    from gnibench.suite.api.verifying import check_scale
    from gnibench.suite.ledger import mutants
    from gnibench.suite.ledger.verify import select_claims

    check_scale(a.scale)
    catalog, _ = mutants.load_catalog()
    known = {m.id: m for m in catalog}
    if a.mutants == "all":
        chosen = catalog
    elif a.mutants.endswith(".toml"):             # held-out mutants, the catalog's schema
        from gnibench.suite.foundation.tomlfile import read_text_file

        chosen, _ = mutants.load_catalog(read_text_file(a.mutants, "--mutants file"), a.mutants)
        if not chosen:
            raise UserError(f"bad --mutants {a.mutants!r}: it lists no [[mutant]]")
    else:
        from gnibench.suite.foundation.errors import unknown

        names = [x.strip() for x in a.mutants.split(",") if x.strip()]
        for n in names:
            if n not in known:
                raise unknown("mutant", n, known)
        chosen = [known[n] for n in names]
    claims = [c.id for c in select_claims(a.claims)] if a.claims and a.claims != ["all"] else []
    from gnibench.suite.runs.reproduce import DEFAULT_DIR

    out = a.output if a.output is not None else DEFAULT_DIR
    tests = getattr(a, "mutant_tests", "auto")
    if tests not in ("auto", "all", "none"):
        raise UserError(f"bad --mutant-tests {tests!r}; allowed: auto, all, none")
    timeout = getattr(a, "mutant_timeout", 3600.0)
    if not (math.isfinite(timeout) and timeout > 0):
        raise UserError(f"bad --mutant-timeout {timeout!r}; allowed: a number of seconds > 0")
    doc = mutants.run_mutants(chosen, out, scale=a.scale, jobs=a.jobs or 2, claims=claims or None,
                              tests=tests, timeout=timeout,
                              log=lambda s: print(s, file=sys.stderr))
    for m in doc["mutants"]:
        by = ", ".join(m["claims"] + m["tests"]) or m["crash"] or m["timeout"]
        print(f"{m['id']:<34} {'killed by ' + by if m['killed'] else 'SURVIVED'}")
    print(f"gnibench: verify: mutation score {doc['killed']}/{doc['total']} at the {doc['scale']} "
          f"scale; {out / 'mutants.json'}", file=sys.stderr)
    return 0 if doc["killed"] == doc["total"] else 1


def _jsonable(x):
    if isinstance(x, float) or hasattr(x, "item"):
        x = float(x)
        return x if math.isfinite(x) else str(x)
    return x
