"""End-to-end cart swing-up (quick mode): the paper's loop and the issue's claims."""
import json

import numpy as np
import pytest
from PIL import Image

from discrepancy_paper.experiments import get_experiment


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    out = get_experiment("cart-swingup")(tmp_path_factory.mktemp("out"), quick=True)
    return out, json.loads((out / "results.json").read_text())


@pytest.mark.slow
def test_writes_report_figures_and_animation(results):
    out, res = results
    for name in ["report.md", "swingup_snapshots.png", "time_series.png", "robustness.png"]:
        assert (out / name).stat().st_size > 1000
    with Image.open(out / "swingup.gif") as gif:
        assert gif.n_frames * gif.info["duration"] >= 2700   # the whole 2.7 s plan, in ms
    assert res["experiment"] == "cart-swingup"


@pytest.mark.slow
def test_identifies_the_exact_discrepancy_from_the_failed_run(results):
    ident = results[1]["identification"]
    assert ident["sin_phi1_coefficient"] == pytest.approx(-1.0, rel=1e-3)
    assert ident["u_coefficient"] == pytest.approx(0.05, rel=1e-3)
    assert ident["other_active_terms"] == []
    assert set(ident["identified_terms"]["phi1"]) == {"sin(phi1)"}


@pytest.mark.slow
def test_flawed_plan_fails_and_hybrid_plans_succeed_on_the_true_system(results):
    runs = results[1]["runs_on_true_system"]
    assert not runs["flawed plan, open loop"]["success"]
    assert not runs["flawed plan + TVLQR"]["success"]
    assert runs["hybrid plan (paper cost) + TVLQR"]["success"]
    assert runs["hybrid plan (min effort), open loop"]["success"]
    for name in ["hybrid plan (paper cost) + TVLQR", "hybrid plan (min effort), open loop"]:
        assert runs[name]["within_rail"]
        assert max(abs(runs[name]["final_state"][0]), abs(runs[name]["final_state"][1])) < 0.05


@pytest.mark.slow
def test_plans_converge_and_the_balancing_plan_is_far_more_sensitive(results):
    res = results[1]
    for plan in res["plans"].values():
        assert plan["ipopt_status"] == "Solve_Succeeded"
        assert plan["max_interval_integration_error"] < 1e-6
    effort = res["plans"]["hybrid_plan_min_effort"]
    assert effort["own_model_replay_final_state_error"] < 0.02
    sens = res["sensitivity"]
    paper = sens["hybrid_plan_paper_cost"]["angle_sensitivity_rad_per_unit_coefficient"]
    low = sens["hybrid_plan_min_effort"]["angle_sensitivity_rad_per_unit_coefficient"]
    assert paper > 100 * low
    assert res["plans"]["hybrid_plan_paper_cost"]["final_time_within_0.2_rad_of_upright_s"] > 1.0


@pytest.mark.slow
def test_robustness_study_quick(results):
    study = results[1]["robustness"]
    n = study["n_cases"]
    assert n == 5 and len(study["cases"]) == n
    factors = np.array([list(c["parameter_factors"].values()) for c in study["cases"]])
    assert np.all(np.abs(factors - 1) <= 0.02 + 1e-12)
    tracked = "hybrid plan (paper cost) + TVLQR"
    assert study["final_state_reached_counts"][tracked] == n   # upright at T, rail ignored
    assert study["success_counts"]["flawed plan, open loop"] == 0
    for name in study["success"]:   # success counts the rail: upright AND within 0.5 m + 1 mm
        travel = np.array(study["max_cart_travel_m"][name])
        upright = np.array(study["final_max_angle_error_rad"][name]) < 0.05
        assert np.all(np.array(study["success"][name]) <= (travel <= 0.501))
        assert sum(study["success"][name]) <= int(np.sum(upright))
    assert study["success_counts"][tracked] == int(np.sum(
        np.array(study["max_cart_travel_m"][tracked]) <= 0.501))


@pytest.mark.slow
def test_differentiating_across_input_jumps_is_worse(results):
    ident = results[1]["identification"]
    other = ident["other_differentiation_methods"]
    assert ident["sin_phi1_relative_error"] < 1e-6 and ident["u_relative_error"] < 1e-6
    whole = other["whole_run_finite_difference"]
    assert whole["u_relative_error"] > 100 * ident["u_relative_error"]
