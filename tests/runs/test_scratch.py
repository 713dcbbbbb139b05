"""Scratch directories of the API (gnibench.run and gnibench.verify without ``output``): removed
when the call ends, and those a killed process left are removed by the next call on the host."""
from __future__ import annotations

import os
import signal
import subprocess
import sys

import pytest


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("GNIBENCH_CACHE_DIR", str(tmp_path / "cache"))
    return tmp_path / "cache"


def test_a_scratch_directory_is_removed_on_return_and_on_an_exception(cache):
    from gnibench.suite.foundation.scratch import scratch_dir

    with scratch_dir("run") as d:
        (d / "x").write_text("1")
        assert d.parent == cache / "scratch" and d.name.startswith("run-")
    assert not d.exists()
    with pytest.raises(RuntimeError), scratch_dir("verify") as d:
        raise RuntimeError
    assert not d.exists()


def test_one_left_by_a_killed_process_goes_with_the_next_call(cache):
    """A process killed by SIGTERM without a handler (Python's default) cannot clean up; the
    next scratch directory made on the host removes it, and never one of a live process."""
    from gnibench.suite.foundation.scratch import scratch_dir

    code = ("from gnibench.suite.foundation.scratch import scratch_dir\n"
            "import sys, time\n"
            "with scratch_dir('verify') as d:\n"
            "    print(d, flush=True); time.sleep(600)\n")
    env = {**os.environ, "GNIBENCH_CACHE_DIR": str(cache)}
    killed = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True,
                              env=env)
    alive = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True,
                             env=env)
    try:
        left = killed.stdout.readline().strip()
        kept = alive.stdout.readline().strip()
        killed.send_signal(signal.SIGTERM)
        killed.wait(timeout=60)
        assert os.path.isdir(left)                     # nothing could remove it
        with scratch_dir("run") as mine:
            assert not os.path.exists(left) and os.path.isdir(kept)
        assert not mine.exists()
    finally:
        alive.kill()
        alive.wait(timeout=60)


def test_run_without_output_leaves_no_directory(cache):
    import gnibench

    res = gnibench.run({"name": "s", "title": "scratch", "reference": "tests", "steps": 5,
                        "cells": [{"problems": ["harmonic-oscillator"],
                                   "methods": ["euler:h=0.1"]}]}, jobs=1)
    assert res.output is None and len(res.cells) == 1
    assert list((cache / "scratch").iterdir()) == []
