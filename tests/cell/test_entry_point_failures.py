"""A broken third-party entry point does not take gnibench down (issue 43 item 4): each is one
warning line naming it and what is allowed, its definitions are skipped, and the shipped
definitions and those of the other entry points stay usable."""
from __future__ import annotations

import importlib.metadata
import sys

import pytest

GOOD = {"kind": "explicit-rk", "order": 1, "c": [0], "A": [[]], "b": [1], "reference": "Euler"}


class _EntryPoint:
    def __init__(self, name, obj):
        self.name, self.value, self._obj = name, f"plugin:{name}", obj

    def load(self):
        if isinstance(self._obj, BaseException):
            raise self._obj
        return self._obj


def _boom():
    raise RuntimeError("boom at load")


BROKEN = [
    ("import-fails", ModuleNotFoundError("No module named 'nosuch'"), "cannot be loaded: "
     "ModuleNotFoundError"),
    ("raises", _boom, "cannot be loaded: RuntimeError: boom at load"),
    ("exits", lambda: sys.exit(4), "cannot be loaded: SystemExit(4)"),
    ("wrong-type", 42, "gives int; allowed: a definition table"),
    ("one-bad", [dict(GOOD, id="ep-fine"), 7], "gives a list whose element 1 is int (7)"),
    ("collides", dict(GOOD, id="rk4"), "method id 'rk4' collides with a shipped one"),
    ("long-id", dict(GOOD, id="a" * 65), "at most 64 characters"),
    ("odd-id", dict(GOOD, id="my euler/é"), "bad id 'my euler/é'"),
]


@pytest.mark.parametrize("name, obj, message", BROKEN, ids=[b[0] for b in BROKEN])
def test_a_broken_entry_point_is_a_warning_and_the_rest_stays_usable(monkeypatch, capsys, name,
                                                                     obj, message):
    from gnibench.methods import METHODS
    from gnibench.suite.cell.spec import parse_method
    from gnibench.suite.cell.user import loader
    from gnibench.suite.foundation import guard

    monkeypatch.setattr(guard, "_watched", [True])      # as under gnibench's signal handlers
    points = [_EntryPoint(name, obj), _EntryPoint("ep-good", dict(GOOD))]
    monkeypatch.setattr(importlib.metadata, "entry_points",
                        lambda group: points if group == "gnibench.methods" else [])
    monkeypatch.setattr(loader, "_discovered", False)
    monkeypatch.delenv("GNIBENCH_LOAD", raising=False)
    try:
        loader.discover()                            # raised a UserError: every command exited 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith("gnibench: warning: entry point "
                                                   f"gnibench.methods:{name}"), err
        assert message in err[0] and err[0].endswith("its definitions are skipped (fix or "
                                                     "uninstall its package)")
        assert "ep-good" in METHODS and "ep-fine" not in METHODS      # nothing of the broken one
        assert parse_method("ep-good:h=0.1").base.record.id == "ep-good"
        assert parse_method("rk4:h=0.1").base.record.id == "rk4"
    finally:
        loader.unload(f"gnibench.methods:{name}")
        loader.unload("gnibench.methods:ep-good")
