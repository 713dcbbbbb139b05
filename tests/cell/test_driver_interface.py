"""One driver interface (issue 18, item 5): the driver objects of suite/cell/drivers.py are the
only callers of the compiled drivers, every slot of their state has a name, one function builds
every Trajectory, and the embedded pairs and odex run one adaptive loop."""
from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
from gnibench.methods.assembly.templates import slots
from gnibench.suite.cell.calls import Buffers
from gnibench.suite.cell.drivers import AdaptiveDriver, FixedStepDriver
from gnibench.suite.cell.solve import solve
from gnibench.suite.cell.spec import prepare
from gnibench.suite.foundation.errors import UserError

ROOT = Path(__file__).resolve().parents[2]


def _sources(*folders):
    for folder in folders:
        for path in (ROOT / folder).rglob("*.py"):
            yield path.relative_to(ROOT).as_posix(), path.read_text()


def test_every_slot_of_the_state_has_one_name():
    assert sorted(slots.SLOTS.values()) == list(range(slots.STATE))
    assert sorted(slots.ROWS.values()) == list(range(slots.Y_ROWS))
    text = slots.slot_constants()
    for name, index in {**slots.SLOTS, **slots.ROWS}.items():
        assert f"{name} = {index}\n" in text


def test_state_slots_are_read_by_name_only():
    """No driver template and no Python module indexes st or y_io with a bare number."""
    bare = re.compile(r"\b(st|y_io)\[\d")
    offenders = [path for path, text in _sources("methods", "suite", "reports") if bare.search(text)]
    assert offenders == []


def test_one_place_builds_a_trajectory():
    builders = [path for path, text in _sources("suite", "methods", "reports")
                if re.search(r"\bTrajectory\(\s*$|\bTrajectory\(\w+=", text, re.MULTILINE)]
    assert builders == ["suite/cell/drivers.py"]


def test_compiled_drivers_are_called_by_the_driver_objects_only():
    call = re.compile(r"kernel\.(integrate|adaptive_)\w*\(")
    offenders = [path for path, text in _sources("suite", "methods", "reports", "tests")
                 if call.search(text)]
    assert offenders == []


def test_one_adaptive_loop_for_the_pairs_and_odex():
    """The embedded pairs' and odex's modules hold the same loop text; only the family parts
    (attempt, controller) differ."""
    from gnibench.methods.assembly import kernel_text

    def loop(spec):
        text = kernel_text(*prepare("kepler-2d", spec))
        start = text.index("def integrate_adaptive(")
        return text[start:]

    assert loop("dopri5") == loop("odex") == loop("dop853")
    for kernel in ("odex.py", "pair.py"):
        assert "while True" not in (ROOT / "methods" / "assembly" / "templates" / kernel).read_text()


def test_driver_objects_read_their_state_by_name():
    problem, method = prepare("kepler-2d", "dopri5:rtol=1e-8,atol=1e-8")
    drv = AdaptiveDriver(problem, method, "integrate_adaptive", 2 * math.pi)
    buffers = Buffers(64, 4, grow=True)
    status, _ = drv.run(buffers, budget=7)
    t, _, c = buffers.arrays()
    assert status == "ok" and drv.t == t[-1] == 2 * math.pi
    assert drv.steps == c[-1, 0] and drv.nfev == c[-1, 1] and drv.rejected == c[-1, 3]
    traj = solve(problem, method, t_end=2 * math.pi)
    assert np.array_equal(traj.t, t) and traj.steps[-1] == drv.steps

    problem, method = prepare("kepler-2d", "rk4:h=0.1")
    drv = FixedStepDriver(problem, method, "integrate", 0.1, 10, 0.1, every=3)
    buffers = Buffers(8, 4, grow=False)
    drv.run(buffers, budget=2)
    assert drv.steps == 10 and drv.t == drv.t_final and drv.slot("ST_LAST_ROW") == 10


def test_reverse_retraces_a_symmetric_method_and_not_rk4():
    def back_and_forth(spec):
        problem, method = prepare("pendulum:p0=0.3,q0=1.0", spec)
        y_n = solve(problem, method, steps=200, every=200).y[-1]
        start = ",".join(f"{s}0={float(v)!r}" for s, v in zip(problem.record.state, y_n))
        back = prepare(f"pendulum:{start}", spec)[0]
        traj = solve(back, method, steps=200, every=200, reverse=True)
        assert traj.t[-1] == pytest.approx(-200 * 0.05) and traj.provenance["reverse"]
        return float(np.max(np.abs(traj.y[-1] - np.array(problem.record.y0(problem.values)))))

    assert back_and_forth("implicit-midpoint:h=0.05") < 1e-13
    assert back_and_forth("rk4:h=0.05") > 1e-9


@pytest.mark.parametrize("spec,kw", [("dopri5", {"t_end": 1.0}), ("rk4:h=0.1", {"t_end": 1.0,
                                                                               "dt_out": 0.3})])
def test_reverse_is_refused_where_it_does_not_apply(spec, kw):
    problem, method = prepare("kepler-2d", spec)
    with pytest.raises(UserError, match="reverse"):
        solve(problem, method, reverse=True, **kw)


def test_a_moved_point_is_not_given_the_fsal_stage_of_the_unmoved_one():
    """dopri5's last stage is f(y1): reused as the next first stage only when neither +projection
    nor post_step moved y1; here every accepted step is projected, so every one costs f(y_n+1) on
    top of HINIT's 2 and the 6 new stages per attempt."""
    traj = solve(*prepare("kepler-2d", "dopri5:rtol=1e-8,atol=1e-8+projection:on=H/L"),
                     t_end=20.0)
    plain = solve(*prepare("kepler-2d", "dopri5:rtol=1e-8,atol=1e-8"), t_end=20.0)
    for tr, extra in ((traj, traj.steps[-1]), (plain, 0)):
        assert tr.nfev[-1] == 2 + 6 * (tr.steps[-1] + tr.rejected[-1]) + extra
