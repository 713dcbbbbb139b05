"""The store across runs (suite/runs/store.py): a part is reused only when it was written in the
store's own format (PART_FORMAT): a part of any other format, older or newer, is discarded with
one warning and recomputed (a cosmic-ray survivor, issue 41: ``!=`` read as ``>``); and a second
run reuses every stored cell unless asked to run fresh (another survivor: the default of fresh)."""
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


def test_run_experiments_reuses_stored_cells_unless_asked_fresh(tmp_path):
    """``gnibench verify`` and ``reproduce`` share one store: by default a second run over the same
    directory reuses every stored cell (run_experiments' default fresh=False)."""
    import io

    from gnibench.suite.runs.experiment import parse_experiment
    from gnibench.suite.runs.runner import run_experiments

    text = ('name = "r"\ntitle = "t"\nreference = "[HLW] I.1"\nsteps = 20\n'
            '[[cells]]\nproblems = ["pendulum"]\nmethods = ["euler:h=0.1", "rk4:h=0.1"]\n')
    logs = []
    for fresh in (None, None, True):
        log = io.StringIO()
        kw = {} if fresh is None else {"fresh": fresh}
        run_experiments([parse_experiment(text, "r.toml")], [tmp_path / "r"], tmp_path, jobs=1,
                        log=log, **kw)
        logs.append(log.getvalue())
    assert "0 reused from the store, 2 to compute" in logs[0]
    assert "2 reused from the store, 0 to compute" in logs[1]
    assert "0 reused from the store, 2 to compute" in logs[2]
