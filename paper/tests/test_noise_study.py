"""`discrepancy reproduce noise-study` (quick): the defaults against known true discrepancies."""
import json

import pytest

from discrepancy_paper.experiments import get_experiment


@pytest.mark.slow
def test_noise_study_quick(tmp_path):
    folder = get_experiment("noise-study")(tmp_path, quick=True)
    results = json.loads((folder / "results.json").read_text())
    # the quick run fits our defaults and PySINDy's (the reproduction adds the paper's
    # settings, the weak form and PySINDy's weak library)
    assert results["methods"] == ["defaults", "PySINDy defaults"]
    for system in ("Van der Pol", "Lorenz"):
        ours = results[system]["defaults"]
        for level in ("0", "0.05"):
            assert ours[level]["right_terms_seeds"] == ours[level]["n_seeds"] == 3
        assert ours["0"]["median_relative_error_of_g"] < 1e-6   # noise-free: exact
        assert ours["0.2"]["median_relative_error_of_g"] < 0.1
        # PySINDy's defaults break at 20 % noise on both systems
        assert results[system]["PySINDy defaults"]["0.2"]["right_terms_seeds"] == 0
    assert (folder / "van_der_pol.png").is_file() and (folder / "lorenz.png").is_file()
