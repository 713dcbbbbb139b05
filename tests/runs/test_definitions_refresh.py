"""``gnibench.solve`` and ``gnibench.run`` load again an edited definitions file (a notebook sees
its edits); a file whose stat has not changed since its text was last found unchanged is not read
again, unless it was modified less than ``RACY_NS`` ago (two same-size writes within one tick of
the file system's clock have the same stat)."""
from __future__ import annotations

import os
import time
from pathlib import Path

import gnibench
import pytest
from gnibench.suite.cell.user import loader

TEXT = ('[[problem]]\nid = "osc-refresh"\nstates = ["q", "p"]\nhamiltonian = "p^2/2 + q^2/2"\n'
        'initial = {q = 1, p = 0}\n')


@pytest.fixture
def reads(monkeypatch):
    """The paths the loader reads with Path.read_text."""
    seen: list[str] = []
    original = Path.read_text

    def counting(self, *args, **kwargs):
        seen.append(str(self))
        return original(self, *args, **kwargs)

    monkeypatch.setattr(Path, "read_text", counting)
    return seen


@pytest.fixture
def loaded(tmp_path):
    path = tmp_path / "osc.toml"
    path.write_text(TEXT)
    gnibench.load(path)
    yield path
    loader.unload(path)


def _age(path: Path, seconds: float) -> None:
    past = time.time_ns() - int(seconds * 1e9)
    os.utime(path, ns=(past, past))


def test_an_old_unchanged_file_is_not_read_again(loaded, reads):
    _age(loaded, 10)
    loader.refresh()                                     # its text found unchanged: stat kept
    assert reads == [str(loaded.resolve())]
    loader.refresh()
    loader.refresh()
    assert len(reads) == 1


def test_a_recent_file_is_read_at_each_refresh(loaded, reads):
    loader.refresh()
    loader.refresh()
    assert len(reads) == 2                               # modified just now: its stat is racy


def test_an_edit_is_seen_after_the_stat_was_kept(loaded, reads):
    _age(loaded, 10)
    loader.refresh()
    loaded.write_text(TEXT.replace("q = 1", "q = 3"))    # same size, a new stat
    q = gnibench.solve("osc-refresh", "rk4:h=0.01", steps=1).samples["q"].iloc[0]
    assert q == 3.0
