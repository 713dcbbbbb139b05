"""The C reference of the adaptive benchmark is the same algorithm as the numba kernel.

suite/runs/bench_c/kepler_adaptive.c ports methods/assembly/templates/adaptive.py and the generated attempt
operation for operation (built with -ffp-contract=off), with the pair's coefficients written from
the same ``Pair`` record (``gnibench.suite.runs.bench.pair_header``). So on kepler-2d the accepted and rejected
step counts must be equal and the final states agree to round-off (measured: bit-identical). This
is what makes the µs/step ratio of ``gnibench bench`` a like-for-like comparison. 10 periods,
rtol = atol = 1e-10; skipped without gcc.
"""
from __future__ import annotations

import math
import shutil
from pathlib import Path

import numpy as np
import pytest
from gnibench.suite.runs.bench import adaptive_cell, build_c_adaptive, run_adaptive, time_c_adaptive

PERIODS = 10


@pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc not found")
@pytest.mark.parametrize("method", ["dopri5", "dop853"])
def test_c_port_takes_the_same_steps(method, tmp_path: Path):
    bound, cfg, pair = adaptive_cell(method)
    y0 = np.array(bound.record.y0(bound.values))
    _, nacc, nrej, nfev, y = run_adaptive(bound, cfg, PERIODS * 2 * math.pi)
    exe = build_c_adaptive(tmp_path, method, pair)
    c = time_c_adaptive(exe, y0, periods=PERIODS, repeats=1)
    assert (c["accepted"], c["rejected"], c["nfev"]) == (nacc, nrej, nfev)
    assert nrej > 0 or method == "dopri5"          # dop853 exercises the rejection branch
    assert np.max(np.abs(c["y"] - y)) <= 1e-13 * np.max(np.abs(y))
