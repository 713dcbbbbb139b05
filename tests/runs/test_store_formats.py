"""The store across runs (suite/runs/store.py): a part is reused only when it was written in the
store's own format (PART_FORMAT): a part of any other format, older or newer, is discarded with
one warning and recomputed (a cosmic-ray survivor, issue 41: ``!=`` read as ``>``); and a second
run reuses every stored cell unless asked to run fresh (another survivor: the default of fresh)."""
from __future__ import annotations

import numpy as np
import pytest
from gnibench.suite.runs import store as S


@pytest.mark.parametrize("shift", [-1, +1])
def test_a_part_of_another_format_is_not_reused(tmp_path, monkeypatch, capsys, shift):
    from gnibench.suite.runs import partfile

    key = "a" * partfile.KEY
    samples = {"t": np.array([0.0, 1.0]), "q": np.array([1.0, 0.5])}
    part = S.Part(samples, {"cell": 0, "status": "ok"}, {"cell": 0}, ("q",))
    own = S.Store(tmp_path / "own").open()
    try:
        own.write(key, part)
    finally:
        own.close()
    assert S.Store(tmp_path / "own").open().read(key) is not None          # its own format
    other = partfile.MAGIC.replace(b"%d" % partfile.FORMAT, b"%d" % (partfile.FORMAT + shift))
    monkeypatch.setattr(partfile, "MAGIC", other)                          # another gnibench
    st = S.Store(tmp_path / "out").open()
    try:
        st.write(key, part)
    finally:
        st.close()
    monkeypatch.undo()
    capsys.readouterr()
    fresh = S.Store(tmp_path / "out").open()                               # this gnibench
    try:
        assert fresh.read(key) is None and not fresh.has(key)
    finally:
        fresh.close()
    assert "written in another format of the store" in capsys.readouterr().err


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
