"""The README is one screen that points to the documentation: at most 150 lines, the two
commands exactly, no measurement log (dates, timings, "on that machine"), and its tour's
commands run; no file of the repository refers to files outside it. The one result it reports,
the score of the last full mutation campaign (issue 41), is checked against the saved campaign,
so it cannot go stale."""
from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
README = (ROOT / "README.md").read_text(encoding="utf-8")
#: the README's section that reports the last full mutation campaign (checked against its file)
CAMPAIGN = README.split("## How far the checks go", 1)[1].split("\n## ", 1)[0]
RUN = ("python3 -m venv .venv && .venv/bin/pip install -e . && .venv/bin/gnibench run quick")
TEST = ("python3 -m venv .venv && .venv/bin/pip install -e '.[test]' && "
        ".venv/bin/python -m pytest -q -n auto")


def test_readme_is_one_screen_with_the_two_commands():
    assert len(README.splitlines()) <= 150
    lines = [line.strip() for line in README.splitlines()]
    assert RUN in lines and TEST in lines


@pytest.mark.parametrize("pattern", [
    r"\b20\d\d-\d\d-\d\d\b",                      # a date
    r"\b\d+(\.\d+)? ?(min|ms|µs|ns)\b",           # a duration
    r"\b\d+ min \d+ s\b|\b\d+(\.\d+)? s\b",       # 5 min 22 s, 64.5 s
    r"(?i)on (that|this|the next) machine",
    r"(?i)\b(cold|warm) (cache|run|kernel)",
    r"(?i)load average",
])
def test_readme_holds_no_measurement_log(pattern):
    text = README.replace(CAMPAIGN, "")
    hits = [line for line in text.splitlines() if re.search(pattern, line)]
    assert hits == [], f"measurement prose in the README: {hits}"


def test_readme_reports_the_last_full_campaign_as_saved():
    """Score, date, commit and every survivor of the newest saved whole-catalog campaign
    (benchmarks/mutants-<date>.json, what the documentation's page shows), and nothing else
    dated in that section."""
    import json

    doc = json.loads(sorted((ROOT / "benchmarks").glob("mutants-20*.json"))[-1].read_text())
    text = " ".join(CAMPAIGN.split())
    assert f"killed {doc['killed']} of {doc['total']} mutants" in text
    assert f"({doc['date']}, commit {doc['commit'][:7]}" in text
    for row in doc["mutants"]:
        assert (f"`{row['id']}`" in text) == (not row["killed"]), row["id"]
    assert re.findall(r"\b20\d\d-\d\d-\d\d\b", text) == [doc["date"]]
    held = [json.loads(sorted((ROOT / "benchmarks").glob(f"mutants-heldout-{k}-new-*.json"))[-1]
                       .read_text()) for k in (1, 2)]
    assert f"scored {held[0]['killed']} of {held[0]['total']} and {held[1]['killed']} of " \
           f"{held[1]['total']}" in text


def _tour() -> list[str]:
    block = README.split("## A ten-line tour", 1)[1].split("```sh", 1)[1].split("```", 1)[0]
    return [line.split("#", 1)[0].strip() for line in block.splitlines() if line.strip()]


def test_the_tour_names_only_what_exists():
    from gnibench.suite.runs.experiment import shipped

    tour = _tour()
    assert 5 <= len(tour) <= 12 and all(c.startswith("gnibench ") for c in tour)
    for command in tour:
        words = shlex.split(command)
        if words[1] == "run" and not words[2].endswith(".toml"):
            assert words[2] in shipped()
        if words[1] == "reproduce":
            assert words[2] in shipped()
    assert any("solve" in c for c in tour)


@pytest.mark.parametrize("command", [c for c in _tour() if c.split()[1] in ("list", "solve")])
def test_the_tours_cheap_commands_run(command, tmp_path):
    words = shlex.split(command)
    if "--reference" in words:                       # a real128 reference is a test of heyoka's
        i = words.index("--reference")
        words[i + 1] = "heyoka"
    out = subprocess.run([sys.executable, "-m", "gnibench.suite.cli.entry", *words[1:]],
                         capture_output=True, text=True, cwd=tmp_path, timeout=600,
                         env=dict(os.environ))
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip()


def test_no_file_refers_to_files_outside_the_repository():
    files = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True,
                           check=True).stdout.split()
    bad = []
    for name in files:
        path = ROOT / name
        if not path.is_file() or path.suffix in (".inv", ".png", ".parquet", ".npz"):
            continue
        try:
            text = path.read_text(encoding="utf-8")
        except UnicodeDecodeError:
            continue
        if re.search(r"\.\./shared|/work/shared|CLAIMS\.md|CATALOG\.md", text):
            bad.append(name)
    bad = [b for b in bad if b != "tests/docs/test_readme.py"]
    assert bad == [], f"files referring outside the repository: {bad}"
