"""The Markdown of saved mutation campaigns (reports/mutation.py), as the docs' page shows it."""
from __future__ import annotations

import json

from gnibench.reports import mutation as M


def campaign(tests="auto", complete=True):
    rows = [{"id": "a", "file": "x.py", "description": "d|a", "killed": True, "claims": ["B-2-a"],
             "tests": [], "crash": "", "timeout": ""},
            {"id": "b", "file": "y.py", "description": "d b", "killed": False, "claims": [],
             "tests": [], "crash": "", "timeout": "", "blind_spot": "below 1 ulp"},
            {"id": "c", "file": "z.py", "description": "d c", "killed": True, "claims": [],
             "tests": ["tests/t/test_x.py::test_y[p]"], "crash": "", "timeout": ""}]
    return {"mutants": rows, "killed": 2, "total": 3, "planned": 3 if complete else 5,
            "complete": complete, "date": "2026-11-28", "commit": "0123456789abcdef",
            "scale": "quick", "tests": tests}


def test_score_line_says_when_where_and_what_ran():
    line = M.score_line(campaign())
    assert line.startswith("**2 of 3 killed** (67 %) on 2026-11-28, commit 0123456789,")
    assert "every test file whose imports reach the mutated file" in line
    assert "a hand-kept list of 2 test files" in M.score_line(campaign(["a", "b"]))
    assert "interrupted: 3 of 5 mutants" in M.score_line(campaign(complete=False))
    doc = campaign()
    doc["mutants"][1]["inconclusive"] = "tests (2 files): tests timed out after 9 s (limit 9 s)"
    assert "(67 %, 1 inconclusive (time limit))" in M.score_line(doc)


def test_tables_name_killers_and_blind_spots(tmp_path):
    table = M.mutant_table(campaign()).splitlines()
    assert table[2] == "| a | `x.py` | d\\|a | claim B-2-a |"
    assert table[3].endswith("| **survived**: below 1 ulp |")
    assert table[4].endswith("| `tests/t/test_x.py::test_y` |")
    both = M.comparison_table({"old": campaign(), "new": {**campaign(), "killed": 3}})
    assert "| b | **survived** | **survived** |" in both and both.endswith("| 2/3 | 3/3 |")
    for name in ("mutants-2026-11-25.json", "mutants-2026-11-28.json"):
        (tmp_path / name).write_text(json.dumps(campaign()))
    assert [p.name for p in M.campaigns(root=tmp_path)][-1] == "mutants-2026-11-28.json"
