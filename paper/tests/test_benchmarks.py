"""The public system-identification benchmarks, run end to end as `discrepancy reproduce`
runs them, held to the bars of the issue that asked for them."""
import json
import math
import re

import pytest

from discrepancy_paper.experiments import get_experiment

pytest.importorskip("casadi")


@pytest.mark.slow
def test_cascaded_tanks_beats_the_bar_with_few_terms(tmp_path):
    """The quick run (the blind procedure scores the linear candidate and the prior alone
    from two origins; every default one, from five, runs in `discrepancy reproduce
    cascaded-tanks`)."""
    folder = get_experiment("cascaded-tanks")(tmp_path, quick=True)
    results = json.loads((folder / "results.json").read_text())
    assert results["number_of_terms"] <= 10
    assert results["test_rms_error_V"] <= 0.40
    assert results["test_rms_error_V"] < results["test_rms_error_prior_alone_V"] / 2
    assert (folder / "test.png").stat().st_size > 10_000
    check_blind_first(folder, results, "test_rms_error_V")
    assert results["quick"]
    assert set(results["blind_procedure"]["candidate_scores"]) == {"prior alone", "linear"}


@pytest.mark.slow
def test_silverbox_arrow_within_a_millivolt_simulated_fast(tmp_path):
    """The quick run (8000 estimation samples, the arrow's first 10 000, the band-limited
    input hold the only one tried besides the default; the whole arrow and every hold are
    `discrepancy reproduce silverbox`): the issue's 1 mV bar and the prior alone."""
    folder = get_experiment("silverbox")(tmp_path, quick=True)
    results = json.loads((folder / "results.json").read_text())
    assert results["quick"] and results["arrow_samples"] == 10_000
    assert results["number_of_terms"] <= 10
    assert results["arrow_rms_error_mV"] <= 1.0
    assert results["arrow_simulation_seconds"] < 5.0
    assert results["arrow_rms_error_prior_alone_mV"] > 10 * results["arrow_rms_error_mV"]
    check_blind_first(folder, results, "test_rms_error_mV")
    assert results["blind_procedure"]["test_rms_error_mV"] < \
        results["arrow_rms_error_prior_alone_mV"]
    # the 1 mV bar for the blind procedure too (0.53 mV on this shortened arrow
    # with the band-limited hold it chooses)
    assert results["blind_procedure"]["test_rms_error_mV"] <= 1.0
    holds = [k for k in results["blind_procedure"]["candidate_scores"] if "u_hold" in k]
    assert [k.split("u_hold=")[1] for k in holds] == ["bandlimited"]


def check_blind_first(folder, results, error_key):
    """The blind procedure's figures exist, are finite and come before any tuned result."""
    blind = results["blind_procedure"]
    assert math.isfinite(blind[error_key]) and blind[error_key] > 0
    assert blind["number_of_terms"] >= 0
    scores = blind["candidate_scores"]
    assert "prior alone" in scores and blind["chosen_candidate"] in scores
    assert all(len(row["forecast_error_per_origin"]) >= 2 for row in scores.values())
    assert blind["fit_cpu_seconds"] > 0
    assert results["tuned_variant"]["chosen_after_seeing_test_numbers"] is True
    assert results["choices_made_after_seeing_results"]
    sections = re.findall(r"^## (.+)$", (folder / "report.md").read_text(), re.M)
    assert sections[0].startswith("Blind procedure"), sections
    assert any(s.startswith("Tuned") for s in sections[1:]), sections
    assert (folder / "candidates.png").stat().st_size > 10_000
