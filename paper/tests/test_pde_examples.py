"""The PDE examples, quick versions run as `discrepancy reproduce` runs them: the blind
procedure finds the true discrepancy, and PDE-FIND with PySINDy's settings gives PySINDy's
coefficients."""
import json

import pytest

from discrepancy_paper.experiments import get_experiment


def check(folder, *, noisy_error: float):
    results = json.loads((folder / "results.json").read_text())
    ours = [s for s in results["summary"] if s["method"] == "ours (prior)"]
    assert {s["noise_percent"] for s in ours} == {0.0, 1.0, 5.0}
    assert all(s["terms_right"] == s["runs"] for s in ours)
    assert max(s["max_coefficient_error_percent"] for s in ours) < noisy_error
    clean = next(s for s in ours if s["noise_percent"] == 0)
    assert clean["max_coefficient_error_percent"] < 0.5
    parity = results["pde_find_same_settings_as_pysindy"]
    assert parity["same_terms"] and parity["max_coefficient_difference"] < 1e-8
    # quick runs: PySINDy's weak form is left to the reproduction (its figures are not
    # checked here); our fits with and without the prior and PySINDy's PDE-FIND run
    assert {s["method"] for s in results["summary"]} == {
        "ours (prior)", "ours (no prior)", "PySINDy pde-find"}
    forecast = results["forecast"]
    assert forecast["relative_rms_error_hybrid_mean"] < forecast["relative_rms_error_prior_mean"]
    for name in ("fields.png", "discrepancy.png", "forecast.png", "report.md"):
        assert (folder / name).stat().st_size > 1000
    return results


@pytest.mark.slow
def test_burgers_with_a_wrong_viscosity(tmp_path):
    check(get_experiment("pde-burgers")(tmp_path, quick=True), noisy_error=2.0)


@pytest.mark.slow
def test_kuramoto_sivashinsky_missing_a_term(tmp_path):
    check(get_experiment("pde-kuramoto-sivashinsky")(tmp_path, quick=True), noisy_error=2.0)


@pytest.mark.slow
def test_reaction_diffusion_missing_its_reaction(tmp_path):
    check(get_experiment("pde-reaction-diffusion")(tmp_path, quick=True), noisy_error=15.0)
