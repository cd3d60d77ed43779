"""End-to-end: `discrepancy reproduce pendulum-energy[-experiment]` (quick versions)."""
import json
import shutil

import numpy as np
import pytest

from discrepancy.errors import DataError
from discrepancy.experiments import pendulum_energy as pe
from discrepancy.experiments import pendulum_energy_measured as pm


def test_encoder_quantisation():
    step = 2 * np.pi / 5000
    x = np.array([[0.3 * step + 1.0, 1.0 + 2.6 * step, 0, 0]])
    q = pe.encoder_angles(x)
    assert np.all(np.abs(q[0, 0] - x[0, 0]) <= step / 2)
    # phi2 is read through the relative encoder: phi1 reading + quantised (phi2 - phi1)
    assert q[0, 1] - q[0, 0] == pytest.approx(round((x[0, 1] - x[0, 0]) / step) * step)


def test_data_folder_from_environment(tmp_path, monkeypatch):
    try:
        real = pm.data_folder()
    except DataError as e:
        pytest.skip(f"measured double pendulum data not available: {e}")
    target = tmp_path / "double_pendulum"
    target.mkdir()
    for name in (pm.RECORDING, pm.PARAMETERS):
        shutil.copy(real / name, target / name)
    monkeypatch.setenv("DISCREPANCY_DATA", str(tmp_path))
    assert pm.data_folder() == target


@pytest.mark.slow
def test_synthetic_quick(tmp_path):
    out = pe.run_synthetic(tmp_path, quick=True)
    results = json.loads((out / "results.json").read_text())
    truth = results["true_parameters"]
    assert truth["k1"] == 7.24e-4 and truth["k2"] == 1.65e-4          # paper's Table 1
    for seed in results["per_seed"]:
        names = {t["name"] for t in seed["identified_terms"]}
        assert names == {"viscous joint 1", "viscous joint 2"}
        assert abs(seed["k1"] / truth["k1"] - 1) < 0.01                # the bar
        assert abs(seed["k2"] / truth["k2"] - 1) < 0.10
        # reconstructing the angles from the encoder counts helps on these seeds
        assert seed["k1_relative_error_percent"] < \
            seed["without_dequantisation"]["k1_relative_error_percent"]
        for name in ("k1", "k2"):      # bootstrap intervals hold the truth
            low, high = seed[f"{name}_95_percent_interval"]
            assert low <= truth[name] <= high
        assert all(t["coefficient"] > 0 for t in seed["identified_terms"])
        # the coefficients' band, carried to the new swing, holds its true energy loss
        assert seed["validation_true_loss_inside_95_percent_band_fraction"] >= 0.8
    state = results["per_seed"][0]["state_form"]
    spans = state["paper library + cos(phi1-phi2) dphi1 dphi2 (spans H_m)"]
    paper = state["paper library (does not span H_m)"]
    assert spans["tautology_warning"] and not paper["tautology_warning"]
    # the tautology: near-exact in training, off by the initial-energy gap on a new swing
    assert spans["training"]["max_abs_percent_of_max"] < 0.1
    assert spans["validation"]["max_abs_percent_of_max"] > 20
    for name in ("fit.png", "energy_training.png", "friction_law.png", "report.md"):
        assert (out / name).is_file()
    # control: the same pipeline on exact angles recovers the true friction (truth known)
    control = results["quantisation_control"]
    assert control["k1_relative_error_percent_exact_angles"] < 0.05
    assert control["k2_relative_error_percent_exact_angles"] < 0.05


@pytest.mark.slow
def test_measured_swing(tmp_path):
    try:
        pm.data_folder()
    except DataError as e:
        pytest.skip(f"measured double pendulum data not available: {e}")
    out = pe.run_experiment(tmp_path)
    results = json.loads((out / "results.json").read_text())
    assert results["split_time_s"] == pytest.approx(69.342, abs=0.05)
    main = results["dissipation_form"]
    assert 1 <= len(main["identified_terms"]) <= 4
    assert all(t["coefficient"] > 0 for t in main["identified_terms"])
    assert main["training"]["max_abs_percent_of_max"] <= 3.0
    for key in ("validation_continued", "validation_restarted_at_window_start"):
        assert np.isfinite(main[key]["max_abs_percent_of_range"])
    # the bar on the validation window (continuing from the training fit)
    assert main["validation_continued"]["max_abs_percent_of_range"] <= pm.VALIDATION_BAR
    assert sum(main["share_of_training_loss_percent"].values()) == pytest.approx(100)
    # other smoothing windows find the same terms
    rows = results["chosen_procedure_with_other_smoothing"]
    assert len({str(r["smoothing"]) for r in rows}) == 4
    names = {t["name"] for t in main["identified_terms"]}
    assert all({t["name"] for t in r["identified_terms"]} == names for r in rows)
    for term in main["identified_terms"]:
        low, high = main["bootstrap_95_percent_intervals"][term["name"]]
        assert 0 <= low <= term["coefficient"] <= high
    # the chosen law's own forecast error lies among those of its bootstrap resamples (a band
    # built without each resample's offset would miss the window by the offset, ~0.2 J)
    spread = main["forecast_band"]["validation_error_of_resampled_laws_percent_of_range"]
    assert spread["2.5 %"] <= main["validation_continued"]["max_abs_percent_of_range"] \
        <= spread["97.5 %"] < 100
    # the procedure is chosen by forecasts inside the training part only
    table = results["procedures"]
    chosen = results["chosen_procedure"]
    assert all(origin + results["forecast_horizon_s"] <= results["split_time_s"] + 1e-6
               for origin in results["forecast_origins_s"])
    assert table[chosen]["forecast_median_percent_of_range"] == \
        min(r["forecast_median_percent_of_range"] for r in table.values())
    assert table[chosen]["validation_continued_percent_of_range"] == \
        pytest.approx(main["validation_continued"]["max_abs_percent_of_range"])
    # the learned law beats the rig file's viscous law on the continued recording
    rig = results["rig_file_viscous_law"]
    assert main["validation_continued"]["max_abs_percent_of_range"] < \
        rig["validation_continued"]["max_abs_percent_of_range"] / 10
    spans = results["state_form"]["paper library + cos(phi1-phi2) dphi1 dphi2 (spans H_m)"]
    assert spans["tautology_warning"]
