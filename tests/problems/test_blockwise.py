"""Exact solutions evaluated by blocks give the values of one array (problems/blockwise.py): the
Newton loop of Kepler's equation sweeps the whole array until every element converged, so a block
evaluated on its own would stop earlier and differ in the last bits of some samples."""
from __future__ import annotations

import numpy as np
import pytest
from gnibench.problems import kepler_2d, kepler_3d
from gnibench.problems.blockwise import Plan


def _blocks(exact, t, y0, values, size, plan):
    parts = []
    for start in range(0, len(t), size):
        with plan.evaluating():
            parts.append(exact(t[start:start + size], y0, values))
    return np.concatenate(parts)


@pytest.mark.parametrize("record, values", [(kepler_2d.PROBLEM, {"e": 0.6}),
                                            (kepler_2d.PROBLEM, {"e": 0.95}),
                                            (kepler_3d.PROBLEM, {})])
@pytest.mark.parametrize("size", [7, 1000])
def test_blocks_give_the_bits_of_one_array(record, values, size):
    values = {p.name: p.default for p in record.params} | values
    y0 = record.y0(values)
    t = np.arange(0, 30001) * 0.003
    whole = record.exact(t, y0, values)
    plan = Plan()
    _blocks(record.exact, t, y0, values, size, plan)          # recording
    assert plan.fix() and plan.counts
    assert np.array_equal(_blocks(record.exact, t, y0, values, size, plan), whole)


def test_a_record_too_short_to_tell_asks_for_another():
    plan = Plan(margin=0)
    with plan.evaluating():                 # converges at sweep 2, then not at sweep 3
        from gnibench.problems.blockwise import sweeps
        sweeps(lambda x: (x + 1, x + 1 == 2), 0, 10)
    with plan.evaluating():
        sweeps(lambda x: (x + 1, x + 1 >= 3), 0, 10)
    assert not plan.fix()
