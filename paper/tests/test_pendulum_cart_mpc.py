"""The single pendulum's MPC campaign end to end (quick mode).

One campaign per module, so that the test workers run the campaigns side by side."""
import pytest

from campaigns import quick_run


@pytest.fixture(scope="module")
def single(tmp_path_factory):
    return quick_run("pendulum-cart-mpc", tmp_path_factory)


@pytest.mark.slow
def test_single_pendulum_campaign_learns_the_exact_terms_and_succeeds(single):
    out, res = single
    assert (out / "nominal_runs.png").stat().st_size > 1000
    exact = res["exact_coefficients"]
    learned = res["learned_from_flawed_attempt"]
    assert learned["ds"]["u"] == pytest.approx(exact["u in (ds)'"], rel=0.05)
    assert learned["dphi"]["cos(phi) u"] == pytest.approx(exact["cos(phi) u in (dphi)'"],
                                                          rel=0.1)
    assert res["nominal_runs"]["hybrid + MPC"]["success"]
    assert not res["nominal_runs"]["flawed + TVLQR"]["success"]
    for route, summary in res["learning_from_flawed_model"]["nominal system"].items():
        rows = summary["coefficients_after_each_attempt"]   # MPC attempts from the flawed model
        assert not rows[0]["success"] and rows[-1]["success"], route
        after = rows[0]["coefficients_after"]
        assert after["ds"]["u"] == pytest.approx(exact["u in (ds)'"], rel=0.05), route
        assert after["dphi"]["cos(phi) u"] == pytest.approx(exact["cos(phi) u in (dphi)'"],
                                                            rel=0.1), route
    study = res["perturbed_cases"]
    assert study["success_counts"]["hybrid + MPC"] == study["n_cases"] == 3
