"""The how-to pages of the reports and sweeps (docs/how-to/reports.md, sweeps.md): their Python
blocks (sweeps.md: its code cells of paired sweeps, families and repeats) run as they are, and their TOML blocks are valid parts of an experiment file."""
from __future__ import annotations

import re
import tomllib
from pathlib import Path

import pytest

DOCS = Path(__file__).resolve().parents[2] / "docs" / "how-to"


@pytest.mark.parametrize("page", ["reports.md", "sweeps.md"])
def test_the_python_blocks_run(page, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    text = (DOCS / page).read_text(encoding="utf-8")
    if page == "sweeps.md":
        # an executed page (MyST-NB, run by the docs build): here its cells from the paired
        # sweeps on, their ``:tags:`` lines dropped
        text = text[text.index("## Paired sweeps"):]
        text = re.sub(r"```\{code-cell\} python\n(?::[^\n]*\n)*\n?", "```python\n", text)
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.DOTALL)
    assert blocks
    for block in blocks:
        exec(compile(block, str(DOCS / page), "exec"), {})                  # noqa: S102
    out = capsys.readouterr().out
    if page == "sweeps.md":
        assert "rtol/atol" in out and "dopri5:adaptive=true" in out
        assert "wall_median_seconds" in out
    else:
        assert "index.html" in out and (tmp_path / "global-error.png").is_file()


def test_the_toml_blocks_are_valid():
    from gnibench.suite.runs.experiment import parse_experiment

    head = 'name = "d"\ntitle = "t"\nreference = "r"\nt_end = 1.0\n'
    cells = ('[[cells]]\nproblems = ["kepler-2d"]\nmethods = ["dop853:adaptive=false", "rk4"]\n'
             'vary.h = [0.1, 0.05, 0.025, 0.0125, 0.01, 0.005, 0.0025]\n')
    sweeps = re.findall(r"```toml\n(.*?)```", (DOCS / "sweeps.md").read_text(), re.DOTALL)
    assert len(parse_experiment(head + sweeps[0], "sweeps.md").cells) == 8
    report = re.findall(r"```toml\n(.*?)```", (DOCS / "reports.md").read_text(), re.DOTALL)
    tomllib.loads(report[0])
    e = parse_experiment(head + report[0] + cells, "reports.md")
    assert e.report["family"] == "dop853" and e.report["cells"] == [3, 7, 12]
