"""The area of a set carried by the flow ([HLW] I.1.3, Figs 1.1 and 1.3): the shoelace formula,
area preservation of the exact flow and of symplectic Euler, explicit Euler's growth, refinement
where the flow stretches the boundary."""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from gnibench.suite.cli.main import main
from gnibench.suite.metrics.area import CarriedSet, carried_area, shoelace

DISC = """
name = "disc"
title = "a disc carried by the pendulum's flow"
reference = "[HLW] Fig 1.3"
steps = {steps}
every = {every}
metrics = ["area{options}"]

[[cells]]
problems = ["pendulum"]
methods = ["{method}"]
[cells.ensemble]
options = ["q0", "p0"]
sample = "circle"
center = [{center}, 0.0]
radius = 0.4
n = {n}
"""


def test_shoelace_of_a_square_and_an_inscribed_polygon():
    assert shoelace(np.array([0.0, 1.0, 1.0, 0.0]), np.array([0.0, 0.0, 1.0, 1.0])) == 1.0
    n = 40
    a = 2 * np.pi * np.arange(n) / n
    assert shoelace(np.cos(a), np.sin(a)) == pytest.approx(n / 2 * math.sin(2 * math.pi / n),
                                                           rel=1e-14)
    assert math.isnan(shoelace(np.array([0.0, np.nan, 1.0]), np.array([0.0, 1.0, 1.0])))


def test_the_identity_changes_no_area_and_refines_nothing():
    s = np.arange(12) / 12
    pts = np.column_stack([np.cos(2 * np.pi * s), np.sin(2 * np.pi * s)])
    states = np.repeat(pts[:, None, :], 3, axis=1)
    carried = CarriedSet(s, np.array([0.0, 1.0, 2.0]), states, states.copy(), (0, 1),
                         lambda new: pytest.fail("nothing is stretched"))
    out = carried_area(carried, {"log": False, "stretch": 3.0, "refine": 4, "max_points": 100})
    assert out["area_change_max"] == 0.0 and out["area_error_final"] == 0.0
    assert out["area_points"] == 12 and out["area_stretched"] == 0


def _run(tmp_path, name, **fields) -> dict:
    text = DISC.format(**{"steps": 3, "every": 1, "options": "", "center": -1.6, "n": 56,
                          **fields})
    (tmp_path / f"{name}.toml").write_text(text)
    out = tmp_path / name
    assert main(["run", str(tmp_path / f"{name}.toml"), "-o", str(out), "-j", "1",
                 "--no-report"]) == 0
    return pd.read_parquet(out / "cells.parquet").iloc[0].to_dict()


def test_hlw_fig_1_3_exact_flow_and_symplectic_euler_keep_area_explicit_euler_does_not(tmp_path):
    """h = t = 1, three steps, a disc of radius 0.4 at (-1.6, 0) ([HLW] Fig 1.3): the exact flow
    (RK4, h = 0.01, against the exact solution) and symplectic Euler keep the area of the polygon
    as the exact flow's polygon does, to the polygon's own discretisation; explicit Euler's
    grows (one step has det 1 + h^2 cos q > 1 near q = 0)."""
    exact = _run(tmp_path, "rk4", method="rk4:h=0.01", steps=300, every=100)
    se = _run(tmp_path, "se", method="symplectic-euler:h=1")
    ee = _run(tmp_path, "ee", method="euler:h=1")
    assert abs(exact["area_error_final"]) < 1e-9                     # RK4 is the exact flow here
    assert abs(exact["area_initial"] - math.pi * 0.16) < 2e-3         # the inscribed polygon
    assert abs(se["area_error_final"]) < 1e-3
    assert ee["area_change_final"] > 0.5 and ee["area_error_final"] > 0.5


def test_refinement_follows_a_stretched_boundary(tmp_path):
    """A disc near the separatrix is sheared by the exact flow over t = 12: refining where it
    stretches adds points and brings the polygon's area closer to the disc's, which the flow
    keeps ([HLW] I.1.3)."""
    common = {"method": "rk4:h=0.01", "steps": 1200, "every": 100, "center": 2.4, "n": 24}
    coarse = _run(tmp_path, "coarse", options=":refine=0", **common)
    fine = _run(tmp_path, "fine", options=":refine=6,stretch=1.5", **common)
    assert fine["area_points"] > coarse["area_points"] == 24
    disc = math.pi * 0.16
    assert abs(fine["area_final"] - disc) < abs(coarse["area_final"] - disc) / 4
