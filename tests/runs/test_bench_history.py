"""Benchmark history: gnibench bench saves each run in pytest-benchmark's layout, --compare fails
above the slowdown threshold against the last saved run of the same machine, and the report's
timing page draws the history."""
from __future__ import annotations

import json
import re

import gnibench.suite.runs.bench
import pytest
from gnibench.reports.timing import history, timing_page
from gnibench.suite.cli.main import main
from gnibench.suite.foundation.benchmarks import last_values, machine_id


def rows(scale: float) -> list[dict]:
    return [{"method": "rk4", "ns_min": 30 * scale, "ns_median": 31 * scale, "c_ns_min": 29.0,
             "c_ns_median": 29.5},
            {"adaptive": True, "method": "dop853", "us_min": 0.2 * scale, "us_median": 0.21 * scale,
             "c_us_min": 0.19, "c_us_median": 0.2, "scipy_us_min": 40.0},
            {"startup": [{"process_seconds": 2.0}, {"process_seconds": 1.0 * scale}]}]


@pytest.fixture
def fake_bench(monkeypatch):
    scale = {"value": 1.0}
    monkeypatch.setattr(gnibench.suite.runs.bench, "bench", lambda **kw: rows(scale["value"]))
    return scale


def test_save_compare_and_threshold(tmp_path, fake_bench, capsys):
    storage = tmp_path / ".benchmarks"
    assert main(["bench", "--storage", str(storage), "--compare"]) == 0
    assert "no earlier run" in capsys.readouterr().out
    files = sorted((storage / machine_id()).iterdir())
    # the commit's id, or "unversioned" outside a git checkout (a copy of the package)
    assert len(files) == 1 and re.match(r"^0001_([0-9a-f]+|unversioned)_\d{8}_\d{6}"
                                        r"(_uncommitted-changes)?\.json$", files[0].name), files[0].name
    doc = json.loads(files[0].read_text())
    names = {b["name"] for b in doc["benchmarks"]}
    assert {"fixed rk4 numba", "fixed rk4 C -O3", "adaptive dop853 numba", "adaptive dop853 C port",
            "adaptive dop853 solve_ivp"} <= names
    fake_bench["value"] = 1.2                                  # 20 % slower: within 1.3x
    assert main(["bench", "--storage", str(storage), "--compare"]) == 0
    fake_bench["value"] = 1.2 * 1.35                           # 35 % slower than the last run
    assert main(["bench", "--storage", str(storage), "--compare"]) == 1
    out = capsys.readouterr().out
    assert "SLOWER" in out and "fixed rk4 numba" in out and "C -O3" not in out.split("compare:")[-1]
    assert main(["bench", "--storage", str(storage), "--compare", "--threshold", "2"]) == 0
    assert len(list((storage / machine_id()).iterdir())) == 4
    assert main(["bench", "--storage", str(storage), "--no-save"]) == 0
    assert len(list((storage / machine_id()).iterdir())) == 4
    assert main(["bench", "--threshold", "0.5"]) == 2
    last = last_values(storage, machine_id())
    assert last["gnibench-bench::fixed rk4 numba"][0] == pytest.approx(31 * 1.2 * 1.35 * 1e-9)


def test_timing_page_draws_the_history(tmp_path, fake_bench):
    storage = tmp_path / ".benchmarks"
    for scale in (1.0, 1.1, 1.5):
        fake_bench["value"] = scale
        assert main(["bench", "--storage", str(storage)]) == 0
    assert len(history(storage)) == 3 * 6
    page = timing_page(storage, tmp_path / "img", "timing")
    assert page["figures"] and (tmp_path / "img" / page["figures"][0]["file"].split("/", 1)[1]).is_file()
    row = next(r for r in page["rows"] if r[0] == "gnibench-bench::fixed rk4 numba")
    assert row[5] == f"{1.5 / 1.1:.2f}" and row[6] == "yes" and row[7] == "3"
