"""[HLW] Ch. I: the figures at the quick scale (files, declared labels, data in every curve), the
ledger's verdicts of every claim of [HLW] at the quick scale (derived from the ledger:
tests/support_figures.py, claims_of), and the measurements of suite/ledger/closed_forms_hlw.py on
synthetic data."""
from __future__ import annotations

import json
import tomllib
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from gnibench.suite.cli.main import main
from gnibench.suite.ledger import closed_forms_hlw
from gnibench.suite.ledger.entries import load_ledger
from gnibench.suite.runs.experiment import shipped
from support_figures import SECTION_FIGURES, check_figure, check_verdicts, claims_of, paper_only, reused_cells

FIGURES = SECTION_FIGURES[Path(__file__).stem]
CLAIMS = claims_of(Path(__file__).stem)


@pytest.fixture(scope="session")    # once per worker (pyproject: --dist loadscope, one worker)
def reproduced(tmp_path_factory):
    out = tmp_path_factory.mktemp("hlw-figures")
    assert main(["reproduce", *FIGURES, "--scale", "quick", "-j", "1", "-o", str(out), "--no-report"]) == 0
    return out


@pytest.mark.parametrize("figure", FIGURES)
def test_figure_files_labels_and_data(reproduced, figure):
    manifest = check_figure(reproduced / figure)       # declared labels, curves, files
    for name in manifest["files"]:                     # table.md too
        assert (reproduced / figure / "figure" / name).stat().st_size > 0, name
    declared = tomllib.loads(shipped()[figure])["figure"]
    if declared.get("kind") == "table":               # the rows as declared, in their order
        rows = manifest["panels"][0]["table"]["rows"]
        assert [r["label"] for r in rows] == [r["label"] for r in declared["table"]["rows"]]


def test_table_2_1_reads_as_the_book_where_it_should(reproduced):
    """The exponents in t and h of the quick table: explicit Euler's energy t¹h¹, Störmer–Verlet's
    energy t⁰h², its L at round-off."""
    manifest = json.loads((reproduced / "hlw-table-2.1" / "figure" / "figure.json").read_text())
    rows = {r["label"]: {e["of"]: e for e in r["measured"]}
            for r in manifest["panels"][0]["table"]["rows"]}
    ee, sv = rows["explicit Euler"]["H"], rows["Störmer–Verlet"]
    assert abs(ee["growth_exponent"] - 1) < 0.2 and abs(ee["order"] - 1) < 0.15
    assert abs(sv["H"]["growth_exponent"]) < 0.1 and abs(sv["H"]["order"] - 2) < 0.15
    assert sv["L"]["zero"]


def test_claims_have_their_expected_verdicts(reproduced, capsys):
    code = main(["verify", *CLAIMS, "--scale", "quick", "-o", str(reproduced), "-j", "1", "--no-report",
                 "--format", "json"])
    captured = capsys.readouterr()
    assert reused_cells(captured.err) > 0           # the figures' cells, from the same store
    rows = {r["id"]: r for r in json.loads(captured.out)}
    assert code == 0, [(i, r["verdict"], r["detail"]) for i, r in rows.items()
                       if r["outcome"] != r["expected"]]
    assert set(rows) == set(CLAIMS) and len(CLAIMS) == 46
    check_verdicts(rows, CLAIMS)
    assert paper_only(CLAIMS) == {"HLW-2.4-d"}                      # 3 million years
    # implicit Euler has no solution near the sun (Newton stops there, margin > 0); [HLW]'s picture
    # comes from the non-converged fixed-point iteration: Jupiter first, then Saturn, thrown away
    assert rows["HLW-2.4-b"]["verdict"] == "partly" and "margin = 0.09" in rows["HLW-2.4-b"]["detail"]
    assert any("newton_failed" in x for x in rows["HLW-2.4-b"]["runs"])
    assert rows["HLW-2.1-table-G-SE"]["verdict"] == "partly"          # O(t h²) from (2.11)
    assert rows["HLW-1.1-b"]["measured"] <= 1e-9
    assert rows["HLW-2.3-d"]["measured"] > 0                          # midpoint anticlockwise
    table = pd.read_parquet(reproduced / "ledger.parquet")
    assert (table["figure"] != "").sum() >= 12


def test_every_hlw_claim_of_the_inventory_is_in_the_ledger():
    from importlib import resources

    text = (resources.files("gnibench.suite") / "claims" / "inventory.txt").read_text()
    inventory = {line for line in text.splitlines() if line.startswith("HLW-")}
    ledger = load_ledger()
    assert len(inventory) == 46 and inventory <= set(ledger)
    for i in inventory:
        assert ledger[i].expected in ("reproduced", "partly", "not reproduced"), i


def _samples(cell, t, **columns):
    return pd.DataFrame({"cell": cell, "t": t, **columns})


def test_asymmetry_sees_a_sheared_orbit_and_not_a_symmetric_one():
    s = np.linspace(0, 2 * np.pi, 20000, endpoint=False)
    q, p = 1.2 * np.cos(s), 0.8 * np.sin(s)
    assert closed_forms_hlw._asymmetry(q, p) < 1e-3
    assert closed_forms_hlw._asymmetry(q + 0.3 * p, p) > 0.1
    # a rotation (q unbounded) is folded onto the circle
    t = np.linspace(0, 40, 40000)
    assert closed_forms_hlw._asymmetry(t, 2 + 0.1 * np.cos(t)) < 1e-2


@pytest.mark.parametrize("seed", range(4))
def test_asymmetry_is_the_brute_force_value(seed):
    """The bounded tree search gives the exact largest nearest distance: the same float as all
    pairwise distances (orbit points and their images at q ± 2π), on sheared and noisy orbits
    whose worst point is not among the every-64th first guesses."""
    rng = np.random.default_rng(seed)
    s = np.sort(rng.uniform(0, 12 * np.pi, 1500))
    q = 2.5 * np.cos(s) + rng.normal(0, 0.05, s.size) + (0.4 * np.sin(s) if seed % 2 else 0.0)
    p = 1.5 * np.sin(s) + rng.normal(0, 0.05, s.size)
    q[rng.integers(s.size)] += 0.7                       # one point well off the others
    qq = np.mod(q + np.pi, 2 * np.pi) - np.pi
    pts = np.column_stack([qq, p])
    images = np.vstack([pts, pts + [2 * np.pi, 0], pts - [2 * np.pi, 0]])
    mirror = np.column_stack([-qq, p])
    brute = np.sqrt(((mirror[:, None, :] - images[None, :, :]) ** 2).sum(-1)).min(1).max()
    assert closed_forms_hlw._asymmetry(q, p) == brute


def test_lv_stages_on_a_periodic_curve():
    """A synthetic cycle whose prey v peaks a quarter period before the predator u; the reversed
    cycle (u three quarters after v) has its maxima in the other order."""
    t = np.arange(0, 20, 0.001)
    theta = 2 * np.pi * t / 5
    u, v = 1 + np.sin(theta), 2 + np.cos(theta)        # v peaks at θ = 0, u a quarter later
    cells = pd.DataFrame({"cell": [0]})
    stages = closed_forms_hlw.lv_stages(cells, _samples(0, t, u=u, v=v))
    assert stages["fraction"] == 1 and stages["cycles"] >= 2
    reverse = closed_forms_hlw.lv_stages(cells, _samples(0, t, u=1 - np.sin(theta), v=v))
    assert reverse["fraction"] == 0


def test_angular_momentum_roundoff_scales():
    t = np.arange(5.0)
    rows = _samples(0, t, q1=[0.4, 1, 1, 1, 1], q2=[0, 0, 0, 0, 0], p1=[0, 0, 0, 0, 0],
                    p2=[2, 2, 2, 2, 2], err_L=[0, 1e-15, 0, 0, 0])
    cells = pd.DataFrame({"cell": [0], "steps": [4]})
    out = closed_forms_hlw.angular_momentum_roundoff(cells, rows)
    eps = np.finfo(float).eps
    assert out["ratio_L"] == pytest.approx(1e-15 / (eps * 0.8 * 2))
    assert out["ratio_qp"] == pytest.approx(1e-15 / (eps * 2 * 2))


@pytest.mark.slow
def test_paper_scale_verdicts(tmp_path, capsys):
    """The paper-scale ledger of [HLW] Ch. I (about 30 s on one core with warm kernels): every
    claim has its expected verdict, HLW-2.4-d (3 million years) included. Runs with -m slow."""
    ids = [i for i in load_ledger() if i.startswith("HLW-")]
    code = main(["verify", *ids, "--scale", "paper", "-o", str(tmp_path / "v"), "-j", "1", "--no-report",
                 "--format", "json"])
    rows = {r["id"]: r for r in json.loads(capsys.readouterr().out)}
    assert code == 0, [(i, r["verdict"]) for i, r in rows.items() if r["outcome"] != r["expected"]]
    assert all(r["verdict"] != "not checkable" for r in rows.values())
