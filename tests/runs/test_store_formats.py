"""A stored part is reused only when it was written in the store's own format, older or newer
(suite/runs/store.py, PART_FORMAT): a part of any other format is discarded with one warning and
recomputed (a cosmic-ray survivor, issue 41: ``!=`` read as ``>``)."""
from __future__ import annotations

import pandas as pd
import pytest
from gnibench.suite.runs import store as S


@pytest.mark.parametrize("shift", [-1, +1])
def test_a_part_of_another_format_is_not_reused(tmp_path, monkeypatch, capsys, shift):
    st = S.Store(tmp_path / "out").open()
    try:
        samples = pd.DataFrame({"t": [0.0, 1.0], "q": [1.0, 0.5]})
        part = S.Part(samples, {"cell": 0, "status": "ok"}, {"cell": 0}, ("q",))
        st.write("k", part, samples.iloc[:0])
        assert st.read("k") is not None                                    # its own format
        fresh = S.Store(tmp_path / "out")                                  # another run
        monkeypatch.setattr(S, "PART_FORMAT", S.PART_FORMAT - shift)       # the code moved on
        assert fresh.read("k") is None and not fresh.has("k")
        assert "cannot be read" in capsys.readouterr().err
    finally:
        st.close()
