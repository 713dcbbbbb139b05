"""A circle of initial points ([cells.points] circle = {center, radius, n}) is n points evenly
spaced on the circle, counterclockwise from angle 0 (suite/runs/scales.py; a cosmic-ray
survivor's class, issue 41)."""
from __future__ import annotations

import math

from gnibench.suite.runs.experiment import parse_experiment


def test_circle_points_are_evenly_spaced_counterclockwise():
    e = parse_experiment('name = "c"\ntitle = "t"\nreference = "[HLW] I.1"\nsteps = 2\n'
                         '[[cells]]\nproblems = ["pendulum"]\nmethods = ["euler:h=0.1"]\n'
                         '[cells.points]\noptions = ["q0", "p0"]\n'
                         'circle = { center = [0.5, -0.25], radius = 0.1, n = 6 }\n', "c.toml")
    (cell,) = e.cells                                    # a point set is one ensemble cell
    ens = cell.ensemble
    got = [dict(zip(ens.options, row)) for row in ens.points]
    assert len(got) == 6 and ens.sample == "circle"
    for k, v in enumerate(got):
        angle = 2 * math.pi * k / 6
        assert math.isclose(v["q0"], 0.5 + 0.1 * math.cos(angle), abs_tol=1e-15)
        assert math.isclose(v["p0"], -0.25 + 0.1 * math.sin(angle), abs_tol=1e-15)
