"""[B] §2-§4 as figures and claims: Figs 1-8 reproduced at the quick scale (files, the declared
axis labels, data in every curve, the numbers the figures show) and the quick-scale verdicts of
the claims B-4.1-a..k, B-3-d, B-2-f (suite/claims/b-4.1.toml, b-3.toml, b-2.toml)."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from gnibench.suite.cli.main import main
from gnibench.suite.ledger.closed_forms_b41 import apsides
from gnibench.suite.ledger.entries import load_ledger
from support_figures import SECTION_FIGURES, check_figure, check_verdicts, claims_of, paper_only, reused_cells

FIGURES = SECTION_FIGURES[Path(__file__).stem]
CLAIMS = claims_of(Path(__file__).stem)       # B-2-f, an aggregate over §5 and §6, runs its parts


@pytest.fixture(scope="session")    # once per worker (pyproject: --dist loadscope, one worker)
def reproduced(tmp_path_factory):
    out = tmp_path_factory.mktemp("b-figures-s4")
    assert main(["reproduce", *FIGURES, "--scale", "quick", "-o", str(out), "-j", "1", "--no-report"]) == 0
    return out


@pytest.mark.parametrize("fig_id", FIGURES)
def test_figure_files_labels_and_data(reproduced, fig_id):
    drawn = check_figure(reproduced / fig_id)        # declared labels, curves, files
    assert set(drawn["cells"]["statuses"]) == {"ok"}
    for got in drawn["panels"]:
        for curve in got["curves"]:
            assert curve["points"] > 1, (fig_id, curve["label"])


def _samples(reproduced, fig_id: str) -> tuple[pd.DataFrame, pd.DataFrame]:
    d = reproduced / fig_id
    return pd.read_parquet(d / "cells.parquet"), pd.read_parquet(d / "samples.parquet")


def _cell(cells, samples, label: str, problem: str = "") -> pd.DataFrame:
    rows = cells[(cells["label"] == label) & cells["problem"].str.contains(problem, regex=False)]
    return samples[samples["cell"] == int(rows["cell"].iloc[0])]


def test_kepler_radial_figures_show_what_the_text_says(reproduced):
    """Figs 1-5 at the quick scale (t <= 1000, μ = p_φ = 1): the RKF orbit is the ellipse of
    H = −0.4; RKF's error grows linearly; Euler's rises to the brink of escape (H̃1 → 0 at
    t ≈ 1016), with the observer it stays bounded, two decades lower."""
    r_p, r_a, _ = apsides(1.0, 1.0, -0.4)
    cells, s = _samples(reproduced, "b-fig-1")
    orbit = _cell(cells, s, "RKF tol 1e-6")
    radius = np.hypot(orbit["q1"], orbit["q2"])
    assert abs(radius.min() - r_p) / r_p < 1e-2 and abs(radius.max() - r_a) / r_a < 1e-2
    cells, s = _samples(reproduced, "b-fig-2")
    assert abs(cells["growth_exponent_H"].iloc[0] - 1) < 0.15
    cells, s = _samples(reproduced, "b-fig-3")
    euler = _cell(cells, s, "Euler h=0.01", "mu=1,p_phi=1,")
    early = float(euler.loc[euler["t"] <= 100, "err_H"].iloc[-1])
    assert euler["err_H"].iloc[-1] > 0.3 and 0.2 > early > 0        # quick growth, near escape
    cells, s = _samples(reproduced, "b-fig-5")
    observed = _cell(cells, s, "Euler h=0.01 + observer θ=1")
    assert observed["err_H"].abs().max() < 0.01 * euler["err_H"].abs().max()
    assert observed["err_H"].max() + (-0.4) < 0


def test_double_oscillator_figures_match_eulers_map(reproduced):
    """Figs 6-8: Euler's energies grow like (1 + h²)ⁿ; the observed ones sit near H0 h/θ."""
    cells, s = _samples(reproduced, "b-fig-6")
    euler = _cell(cells, s, "Euler h=1e-3")
    n = euler["steps"].to_numpy(float)
    assert np.allclose(euler["err_H1"], 1.5 * ((1 + 1e-6) ** n - 1), rtol=1e-8, atol=1e-14)
    both = _cell(cells, s, "Euler h=1e-3 + observer H1/H2")
    assert abs(both["err_H1"].iloc[-1] / (1.5 * 1e-3 / 1000) - 1) < 0.05
    cells, s = _samples(reproduced, "b-fig-7")
    euler = _cell(cells, s, "Euler h=0.1")
    at55 = euler[euler["steps"] == 55]
    assert float(at55["err_H1"].iloc[0]) > 1 and float(at55["err_H2"].iloc[0]) > 1
    observed = _cell(cells, s, "Euler h=0.1 + observer H1/H2")
    assert observed[["err_H1", "err_H2"]].abs().to_numpy().max() <= 0.02
    cells, s = _samples(reproduced, "b-fig-8")
    plain = _cell(cells, s, "Euler h=1e-3")["err_H2"].abs().iloc[-1]
    on_h1 = _cell(cells, s, "Euler h=1e-3 + observer H1")["err_H2"].abs().iloc[-1]
    assert on_h1 < plain / 2


def test_apsides_closed_form():
    r_p, r_a, period = apsides(1.0, 1.0, -0.4)
    assert math.isclose(r_p, (1 - math.sqrt(0.2)) / 0.8, rel_tol=1e-14)
    assert math.isclose(r_a, (1 + math.sqrt(0.2)) / 0.8, rel_tol=1e-14)
    assert math.isclose(period, 2 * math.pi * 1.25 ** 1.5, rel_tol=1e-14)
    r_p, r_a, _ = apsides(2.0, 2.0, -0.4)                    # roots of H0 r² + μ r − p_φ²/2
    for r in (r_p, r_a):
        assert abs(-0.4 * r * r + 2.0 * r - 2.0) < 1e-12


def test_quick_scale_verdicts(reproduced, capsys):
    """Every claim of §2-§4 has its expected outcome at the quick scale, or is skipped there
    (scale = "paper")."""
    code = main(["verify", *CLAIMS, "--scale", "quick", "-o", str(reproduced), "-j", "1", "--no-report",
                 "--format", "json"])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert reused_cells(captured.err) > 0           # the figures' cells, from the same store
    rows = {r["id"]: r for r in json.loads(captured.out)}
    ledger = load_ledger()
    assert set(CLAIMS) <= set(rows)
    check_verdicts(rows, CLAIMS)
    assert paper_only(CLAIMS) == {"B-4.1-a", "B-4.1-b", "B-4.1-c", "B-4.1-f", "B-4.1-g",
                                  "B-4.1-i", "B-4.1-k"}
    assert rows["B-4.1-e"]["measured"] == 1.0
    assert rows["B-3-d"]["verdict"] == "reproduced"
    for cid in ("B-4.1-a", "B-4.1-b", "B-4.1-c", "B-4.1-d", "B-4.1-f", "B-4.1-g", "B-4.1-h",
                "B-4.1-i", "B-4.1-k", "B-3-d"):
        assert ledger[cid].figure in FIGURES, cid


@pytest.mark.slow
def test_paper_scale_verdicts(tmp_path, capsys):
    """The claims of §2-§4 at the paper scale (the aggregate B-2-f aside: its parts are §5's and
    §6's, judged at the paper scale by their files)."""
    own = [c for c in CLAIMS if not load_ledger()[c].all_of]
    code = main(["verify", *own, "--scale", "paper", "-o", str(tmp_path), "-j", "1", "--no-report",
                 "--format", "json"])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    ledger = load_ledger()
    for row in json.loads(captured.out):
        assert row["outcome"] == ledger[row["id"]].expected, (row["id"], row["measured"])


def test_radial_kepler_shape_from_the_levels_not_the_samples():
    """B-4.1-c: with 2-3 samples per orbit (RKF in ledger-b-4.1) the sampled min r, max r miss the
    apsides; the apsides of the samples' levels do not depend on the sampling."""
    from gnibench.problems.kepler_exact import solve_kepler
    from gnibench.suite.ledger.closed_forms_b41 import kepler_radial_apsides

    mu, p_phi, H0 = 1.0, 1.0, -0.4
    r_p, r_a, period = apsides(mu, p_phi, H0)
    a, e = (r_p + r_a) / 2, (r_a - r_p) / (r_a + r_p)
    t = np.arange(0.0, 200 * period, period / 2.6)             # 2.6 samples per orbit
    E = solve_kepler(2 * np.pi * t / period, e)      # from the pericenter, [HLW] I.2.2, (2.1)
    r = a * (1 - e * np.cos(E))
    cells = pd.DataFrame([{"cell": 0, "problem": f"kepler-radial:mu={mu},p_phi={p_phi},H0={H0}"}])
    exact = kepler_radial_apsides(cells, pd.DataFrame({"cell": 0, "t": t, "r": r, "err_H": 0.0}))
    assert exact["level_deviation"] == 0 and exact["deviation"] > 1e-3
    assert 2.5 <= exact["samples_per_orbit"] <= 2.7
    drift = kepler_radial_apsides(cells, pd.DataFrame({"cell": 0, "t": t, "r": r,
                                                       "err_H": 1e-3 * t / t[-1]}))
    p1, a1, _ = apsides(mu, p_phi, H0 + 1e-3)
    assert abs(drift["level_deviation"] - max(abs(p1 - r_p) / r_p, abs(a1 - r_a) / r_a)) < 1e-15
