"""Automatic STLSQ threshold (blocked cross-validation over the threshold path; BIC without
folds) against known true supports."""
import numpy as np
import pytest

import discrepancy as dc
from discrepancy.errors import ParameterError


def fit_vdp(x, prior, threshold):
    return dc.DiscrepancyModel(prior=prior, feature_library=dc.PolynomialLibrary(degree=4),
                               optimizer=dc.STLSQ(threshold=threshold),
                               differentiation_method=dc.SavitzkyGolay(31, 3)).fit(x, t=0.01)


@pytest.mark.parametrize("noise", [0.01, 0.1])
def test_auto_threshold_finds_true_support_of_vdp_parameter_case(vdp_data, helpers, noise):
    """True discrepancy 0.4 x2 - 0.4 x1^2 x2; noise 10x the paper's at the upper end."""
    prior = helpers.vdp_rhs(0.1)
    for seed in range(3):
        x = vdp_data.x + noise * np.random.default_rng(seed).standard_normal(vdp_data.x.shape)
        model = fit_vdp(x, prior, "auto")
        names, coef = model.get_feature_names(), model.coefficients()
        active = {(i, names[j]) for i, j in zip(*np.nonzero(coef), strict=True)}
        assert active == {(1, "x2"), (1, "x1^2 x2")}
        assert coef[1, names.index("x2")] == pytest.approx(0.4, rel=0.08)


def test_auto_threshold_result_equals_fixed_threshold_it_chose(vdp_data, helpers):
    x = vdp_data.x + 0.02 * np.random.default_rng(5).standard_normal(vdp_data.x.shape)
    auto = fit_vdp(x, helpers.vdp_rhs(0.1), "auto")
    chosen = auto.optimizer_.thresholds_[1]
    fixed = fit_vdp(x, helpers.vdp_rhs(0.1), float(chosen))
    np.testing.assert_allclose(auto.coefficients()[1], fixed.coefficients()[1], rtol=1e-12)


def test_auto_threshold_on_random_sparse_regressions_recovers_support():
    rng = np.random.default_rng(11)
    hits = 0
    for _ in range(10):
        theta = rng.standard_normal((4000, 20))
        xi = np.zeros((20, 2))
        xi[rng.choice(20, 3, replace=False), 0] = rng.uniform(0.5, 2, 3)
        xi[rng.choice(20, 4, replace=False), 1] = -rng.uniform(0.5, 2, 4)
        y = theta @ xi + 0.3 * rng.standard_normal((4000, 2))
        coef = dc.STLSQ(threshold="auto").fit(theta, y).coef_
        hits += np.array_equal(coef != 0, xi.T != 0)
    assert hits >= 9


def test_auto_threshold_needs_sums_of_squares_from_fit_gram():
    theta = np.random.default_rng(0).standard_normal((100, 3))
    with pytest.raises(ParameterError, match="yy"):
        dc.STLSQ(threshold="auto").fit_gram(theta.T @ theta, theta.T @ theta[:, :1])


def test_model_default_optimizer_needs_no_threshold(vdp_data, helpers):
    """Defaults only (no optimizer given): the paper's discrepancy is found from noisy data."""
    x = vdp_data.x + 0.01 * np.random.default_rng(9).standard_normal(vdp_data.x.shape)
    model = dc.DiscrepancyModel(prior=helpers.vdp_rhs(0.1),
                                feature_library=dc.PolynomialLibrary(degree=3),
                                differentiation_method=dc.SavitzkyGolay(31, 3)).fit(x, t=0.01)
    names, coef = model.get_feature_names(), model.coefficients()
    assert {(i, names[j]) for i, j in zip(*np.nonzero(coef), strict=True)} == {
        (1, "x2"), (1, "x1^2 x2")}


# ----------------------------------------------------- blocked cross-validation

def test_wide_smoothing_windows_no_longer_add_terms(vdp_data, helpers):
    """Savitzky-Golay 101: BIC counted the correlated residuals as independent samples and
    kept extra terms in every seed; blocked cross-validation does not."""
    prior = helpers.vdp_rhs(0.1)
    right = 0
    for seed in range(5):
        x = vdp_data.x + 0.1 * np.random.default_rng(seed).standard_normal(vdp_data.x.shape)
        model = dc.DiscrepancyModel(prior=prior, feature_library=dc.PolynomialLibrary(3),
                                    differentiation_method=dc.SavitzkyGolay(101, 3)).fit(
            x, t=0.01)
        names = model.get_feature_names()
        active = {(i, names[j]) for i, j in zip(*np.nonzero(model.coef_), strict=True)}
        right += active == {(1, "x2"), (1, "x1^2 x2")}
    assert right >= 4


def test_cross_validated_errors_equal_explicit_refits_on_the_other_folds():
    """The fold errors from Gram statistics equal least squares refitted by numpy on the
    explicit rows of the other folds and evaluated on the held-out rows."""
    from discrepancy.optimizers.gram import GramStatistics
    from discrepancy.optimizers.selection import cross_validated_errors

    rng = np.random.default_rng(3)
    theta, y = rng.standard_normal((1000, 6)), rng.standard_normal((1000, 2))
    stats = GramStatistics(6, 2, 5, 64).add(theta, y)
    support = np.array([True, False, True, True, False, False])
    fold = (np.arange(1000) // 64) % 5
    for i in range(2):
        expected = []
        for f in range(5):
            train, test = fold != f, fold == f
            coef = np.linalg.lstsq(theta[train][:, support], y[train, i], rcond=None)[0]
            expected.append(np.mean((y[test, i] - theta[test][:, support] @ coef) ** 2))
        np.testing.assert_allclose(cross_validated_errors(stats, i, support, 0.0), expected,
                                   rtol=1e-9)


def test_selection_path_is_kept_and_the_chosen_point_is_on_it(vdp_data, helpers):
    x = vdp_data.x + 0.05 * np.random.default_rng(1).standard_normal(vdp_data.x.shape)
    model = dc.DiscrepancyModel(prior=helpers.vdp_rhs(0.1),
                                feature_library=dc.PolynomialLibrary(3)).fit(x, t=0.01)
    path = model.optimizer_.selection_[1]
    assert path["criterion"] == "blocked cross-validation"
    chosen = path["chosen"]
    assert path["n_terms"][chosen] == np.count_nonzero(model.coef_[1]) == 2
    best = int(np.argmin(path["error"]))
    assert path["error"][chosen] <= path["error"][best] + path["error_se"][best]
    assert path["n_terms"][-1] == 0  # the path runs down to the empty model


def test_exact_prior_on_noise_free_data_learns_nothing(vdp_data, helpers):
    """Derivatives are estimated (not given); the numerical error left must not become
    terms of 1e-9."""
    model = dc.DiscrepancyModel(prior=helpers.vdp_rhs(0.5),
                                feature_library=dc.PolynomialLibrary(3)).fit(vdp_data.x, t=0.01)
    assert not model.coef_.any()


def test_selection_figure_draws_the_path_and_marks_the_choice(vdp_data, helpers):
    import matplotlib

    matplotlib.use("Agg")
    from discrepancy.plots.selection import selection_figure

    x = vdp_data.x + 0.05 * np.random.default_rng(1).standard_normal(vdp_data.x.shape)
    model = dc.DiscrepancyModel(prior=helpers.vdp_rhs(0.1),
                                feature_library=dc.PolynomialLibrary(3)).fit(x, t=0.01)
    fig = selection_figure(model)
    ax = fig.axes[1]
    chosen = [line for line in ax.get_lines() if line.get_label().startswith("chosen")][0]
    assert chosen.get_xdata()[0] == 2 == np.count_nonzero(model.coef_[1])
    path = model.optimizer_.selection_[1]
    assert list(ax.get_lines()[0].get_xdata()) == path["n_terms"]


def test_too_few_samples_for_the_folds_fall_back_to_bic_with_a_warning():
    """12 samples (PySINDy's test data) hold one 16-sample fold: BIC chooses instead, with a
    warning, and on exact data it finds exactly the true terms."""
    t = np.arange(12) * 0.1
    x = np.c_[t, t ** 2]               # x1' = 1, x2' = 2 x1: exact for finite differences
    with pytest.warns(dc.errors.ShortRecordWarning, match="blocks of 16 samples.*have 12"):
        auto = dc.DiscrepancyModel(differentiation_method="finite_difference").fit(x, t=0.1)
    assert auto.optimizer_.selection_[0]["criterion"] == "BIC"
    names = auto.get_feature_names()
    found = [{names[j]: c for j, c in enumerate(row) if c} for row in auto.coef_]
    assert found[0] == pytest.approx({"1": 1.0}) and found[1] == pytest.approx({"x1": 2.0})
    fixed = dc.DiscrepancyModel(differentiation_method="finite_difference",
                                optimizer=dc.STLSQ(threshold=0.1)).fit(x, t=0.1)
    assert fixed.coef_[1, 1] == pytest.approx(2.0, rel=1e-6)


def test_short_records_get_short_folds():
    """400 samples: segments of 32 rows, five folds, the automatic threshold works."""
    t = np.arange(400) * 0.05
    x = np.exp(-0.1 * t)[:, None] * np.c_[np.sin(t), np.cos(t)]
    model = dc.DiscrepancyModel(feature_library=dc.PolynomialLibrary(2)).fit(x, t=0.05)
    assert model.setup_.fold_segment == 32 and len(model.statistics_.usable_folds()) == 5
    names = model.get_feature_names()
    assert {names[j] for j in np.flatnonzero(model.coef_[0])} == {"x1", "x2"}
