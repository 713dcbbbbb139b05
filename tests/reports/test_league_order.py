"""A league table lists every ranked family before the unranked ones, however many are ranked
(reports/league.py; a cosmic-ray survivor's class, issue 41: the sort key of the unranked rows
was only checked with fewer than nine families)."""
from __future__ import annotations

import numpy as np
import pandas as pd
from gnibench.reports.league import league


def test_unranked_families_come_last_among_many():
    fams = [f"f{k:02d}" for k in range(12)]
    cells = pd.DataFrame({"cell": range(13), "family": fams + ["broken"],
                          "status": ["ok"] * 12 + ["nonfinite"], "reason": [""] * 12 + ["x"],
                          "nfev": [100.0 * (k + 1) for k in range(12)] + [10.0],
                          "max_global_error": [1e-9] * 12 + [np.inf]})
    cells["setup"] = cells["cell"]                  # each family one setup (reports/setups.py)
    cells["swept"] = ""
    wall = {k: 1e-3 * (k + 1) for k in range(13)}
    rows = league(cells, wall, 1e-8)
    assert [r.family for r in rows] == fams + ["broken"]
    assert [r.rank_nfev for r in rows] == list(range(1, 13)) + [None]
