"""The energy-systems experiment (quick): systems built from T and V, fitted with defaults."""
import json

import pytest

from discrepancy_paper.experiments import energy_systems


@pytest.mark.slow
def test_energy_systems_quick(tmp_path):
    out = energy_systems.run(tmp_path, quick=True)
    results = json.loads((out / "results.json").read_text())
    for name in energy_systems.SYSTEMS:
        for row in results[name]["defaults_fit"]:
            assert row["right_terms"], (name, row["found"])
            assert all(abs(e) < 2 for e in row["coefficient_errors_percent"].values())
    blind = results["single pendulum"]["blind_protocol"]
    assert len(blind) == 2
    for row in blind:
        assert row["validation_continued_percent_of_range"] < 15
        assert 0.5 <= row["form_band_coverage_of_validation"] <= 1
    assert (out / "blind_validation.png").stat().st_size > 10_000
