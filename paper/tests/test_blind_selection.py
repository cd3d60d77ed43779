"""`discrepancy reproduce blind-selection` (quick): the must-shows against known truths."""
import json

import pytest

from discrepancy_paper.experiments import get_experiment


@pytest.mark.slow
def test_blind_selection_quick(tmp_path):
    folder = get_experiment("blind-selection")(tmp_path, quick=True)
    results = json.loads((folder / "results.json").read_text())
    default = "forecasts (default)"
    for system, counts in results["prior_only_seeds_of_3"].items():   # exact priors
        assert counts[default] == 3, system
    assert results["damping_found_seeds_of_3"][default] == 3
    assert results["exact_terms_seeds_of_3"]["Duffing, weak damping missing"][default] == 3
    disturbance = results["disturbance"]
    assert disturbance["chosen_hybrid_no_worse_than_prior"]
    chosen = next(k for k in disturbance["models"] if k.startswith("chosen"))
    assert disturbance["models"][chosen]["equations"][1] != "prior"
    assert "left the region" in disturbance["extrapolation_warning"]
    repeated = results["disturbance_over_seeds"]      # other phases and noise, same push
    assert len(repeated["seeds"]) == 2
    assert repeated["chosen_hybrid_no_worse_than_prior_alone_seeds"]["whole test record"] == 2
    for run in repeated["k_step_rms_error_per_seed"]:
        for horizon, errors in run["chosen hybrid"].items():
            prior = run["prior alone"][horizon]["whole test record"]
            assert errors["whole test record"] <= prior, (run["seed"], horizon)
    for name in ("seeds.png", "forecast_selection.png", "libraries.png", "disturbance.png"):
        assert (folder / name).is_file()
