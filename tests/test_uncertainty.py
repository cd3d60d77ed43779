"""Block bootstrap uncertainty against the spread over independent repeated experiments."""
import numpy as np
import pytest

import discrepancy as dc
from discrepancy.errors import NotFittedError, ParameterError


def fit(x, prior):
    return dc.DiscrepancyModel(prior=prior, feature_library=dc.PolynomialLibrary(degree=4),
                               optimizer=dc.STLSQ(threshold=0.05),
                               differentiation_method=dc.SavitzkyGolay(31, 3)).fit(x, t=0.01)


@pytest.fixture(scope="module")
def repeated(vdp_data):
    """Coefficients of x2 and x1^2 x2 over 30 independent noise seeds (the truth to compare)."""
    from tests.conftest import vdp_rhs

    est = []
    for seed in range(30):
        x = vdp_data.x + 0.02 * np.random.default_rng(1000 + seed).standard_normal(
            vdp_data.x.shape)
        model = fit(x, vdp_rhs(0.1))
        names = model.get_feature_names()
        est.append(model.coefficients()[1, [names.index("x2"), names.index("x1^2 x2")]])
    return np.std(est, axis=0, ddof=1)


@pytest.mark.parametrize("seed", [0, 1])
def test_wild_bootstrap_std_is_close_to_and_not_below_repeated_experiments(
        vdp_data, helpers, repeated, seed):
    x = vdp_data.x + 0.02 * np.random.default_rng(seed).standard_normal(vdp_data.x.shape)
    model = fit(x, helpers.vdp_rhs(0.1))
    unc = model.bootstrap(x, t=0.01, n_resamples=300, seed=seed)
    names = model.get_feature_names()
    std = unc.std[1, [names.index("x2"), names.index("x1^2 x2")]]
    ratio = std / repeated
    assert np.all(ratio > 0.6) and np.all(ratio < 3.0), ratio


def test_true_terms_always_included_and_intervals_cover_truth(vdp_data, helpers):
    x = vdp_data.x + 0.02 * np.random.default_rng(3).standard_normal(vdp_data.x.shape)
    model = fit(x, helpers.vdp_rhs(0.1))
    unc = model.bootstrap(x, t=0.01, n_resamples=200)
    names = model.get_feature_names()
    j2, j3 = names.index("x2"), names.index("x1^2 x2")
    assert unc.inclusion_probability[1, j2] == 1.0 and unc.inclusion_probability[1, j3] == 1.0
    low, high = unc.interval(0.99)
    assert low[1, j2] < 0.4 < high[1, j2] and low[1, j3] < -0.4 < high[1, j3]
    table = unc.table()
    assert "x1^2 x2" in table and "included" in table


def test_pairs_bootstrap_is_wider_than_wild(vdp_data, helpers):
    x = vdp_data.x + 0.02 * np.random.default_rng(4).standard_normal(vdp_data.x.shape)
    model = fit(x, helpers.vdp_rhs(0.1))
    j = model.get_feature_names().index("x2")
    wild = model.bootstrap(x, t=0.01, method="wild").std[1, j]
    pairs = model.bootstrap(x, t=0.01, method="pairs").std[1, j]
    assert pairs > wild


def test_bootstrap_bad_input(vdp_data, helpers):
    model = fit(vdp_data.x, helpers.vdp_rhs(0.1))
    with pytest.raises(ParameterError, match="method"):
        model.bootstrap(vdp_data.x, t=0.01, method="jackknife")
    with pytest.raises(ParameterError, match="only 4 blocks"):
        model.bootstrap(vdp_data.x[:200], t=0.01, block_length=64)
    with pytest.raises(ParameterError, match="divides the fit's cross-validation segment"):
        model.bootstrap(vdp_data.x, t=0.01, block_length=100)
    for bad in (0, 1, True):
        with pytest.raises(ParameterError, match="n_resamples must be an integer >= 2"):
            model.bootstrap(vdp_data.x, t=0.01, n_resamples=bad)
    with pytest.raises(NotFittedError):
        dc.DiscrepancyModel().bootstrap(vdp_data.x, t=0.01)


# --------------------------------------------------------------- forecast bands

@pytest.fixture(scope="module")
def noisy_fit(vdp_data, helpers):
    x = vdp_data.x + 0.05 * np.random.default_rng(4).standard_normal(vdp_data.x.shape)
    model = dc.DiscrepancyModel(prior=helpers.vdp_rhs(0.1),
                                feature_library=dc.PolynomialLibrary(3)).fit(x, t=0.01)
    return model, model.bootstrap(x, t=0.01, n_resamples=100)


def test_print_shows_each_coefficient_with_its_bootstrap_std(noisy_fit, capsys):
    model, unc = noisy_fit
    model.print(uncertainty=unc)
    line = capsys.readouterr().out.splitlines()[1]
    j = model.get_feature_names().index("x2")
    assert f"({model.coef_[1, j]:.3f} ± {unc.std[1, j]:.3f}) x2" in line


def test_prediction_band_holds_the_true_derivative_on_a_new_trajectory(noisy_fit,
                                                                        vdp_validation):
    model, unc = noisy_fit
    low, high = model.predict_interval(vdp_validation.x, uncertainty=unc)
    inside = (low <= vdp_validation.x_dot) & (vdp_validation.x_dot <= high)
    assert inside[:, 0].all()            # the kinematic equation is exact (no term learned)
    assert inside[:, 1].mean() > 0.8
    assert np.all(high - low >= 0) and (high[:, 1] - low[:, 1]).max() > 0


def test_simulation_band_holds_the_true_new_trajectory(noisy_fit, vdp_validation):
    model, unc = noisy_fit
    t = vdp_validation.t[:800]
    low, high = model.simulate_interval(vdp_validation.x[0], t, uncertainty=unc, n_draws=40)
    truth = vdp_validation.x[:800]
    assert ((low <= truth) & (truth <= high)).mean() > 0.8
    # a wrong model's trajectory (the prior alone) lies outside the band
    prior_only = model.with_coefficients(np.zeros_like(model.coef_)).simulate(truth[0], t)
    assert ((low <= prior_only) & (prior_only <= high)).mean() < 0.5


def test_bands_refuse_another_models_uncertainty(noisy_fit, vdp_data):
    model, unc = noisy_fit
    other = dc.DiscrepancyModel(feature_library=dc.PolynomialLibrary(2)).fit(
        vdp_data.x, t=0.01)
    with pytest.raises(ParameterError, match="this model's bootstrap"):
        other.predict_interval(vdp_data.x, uncertainty=unc)
    with pytest.raises(ParameterError, match="level"):
        model.predict_interval(vdp_data.x, uncertainty=unc, level=1.5)
