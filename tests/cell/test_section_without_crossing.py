"""A section run that finds no crossing is a result, not a crash (found by the cosmic-ray campaign,
issue 41: the counters of an empty trajectory).

Its table has no rows, its status says how many crossings it found, and its cost counters are 0
(never negative, never missing), through the API and the command line alike.
"""
from __future__ import annotations

import json

import gnibench
from gnibench.suite.cli.main import main


def test_no_crossing_is_an_empty_table_with_its_reason(capsys):
    traj = gnibench.solve("henon-heiles", "rk4:h=0.1", steps=2, section=1)
    assert traj.status == "ok" and len(traj.samples) == 0
    assert "only 0 of 1 crossings" in traj.reason
    assert traj.meta["njev"] == 0.0 and traj.meta["crossings_found"] == 0
    assert main(["solve", "henon-heiles", "rk4:h=0.1", "--steps", "2", "--section", "1",
                 "--format", "json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["meta"]["njev"] == 0.0
