"""PySINDy's options side by side with PySINDy 2.x on identical input (issue 23): short
records, sample weights, the traps (t, live coefficients, differentiation calls, discrete
simulation keywords, constraint order, names) and the solvers and options that were missing
(ensembles, SR3 per-term weights and trimming, ConstrainedSR3, FiniteDifference options,
feature_names, integrator_kws, metric_kws, u as one number). Same numbers to 1e-8, or the
difference the user guide documents (docs/guide/pysindy.md)."""
import warnings

import numpy as np
import pysindy as ps
import pytest
from scipy.integrate import solve_ivp
from sklearn.linear_model import ElasticNet, Lasso
from sklearn.metrics import mean_squared_error, r2_score

import discrepancy as dc
from discrepancy.errors import NameConventionWarning, ParameterError, ShortRecordWarning
from pysindy_helpers import pysindy_defaults, quiet

warnings.filterwarnings("ignore", category=UserWarning, module="pysindy")
TOL = dict(rtol=1e-8, atol=1e-8)


def lorenz_rhs(t, z):
    return [10 * (z[1] - z[0]), z[0] * (28 - z[2]) - z[1], z[0] * z[1] - 8 / 3 * z[2]]


def lorenz_run(t, x0=(8, 27, -7)):
    return solve_ivp(lorenz_rhs, (t[0], t[-1]), x0, t_eval=t, rtol=1e-10, atol=1e-10).y.T


@pytest.fixture(scope="module")
def short_lorenz():
    """PySINDy's test data: 12 samples of Lorenz over one time unit."""
    t = np.linspace(0, 1, 12)
    return lorenz_run(t), t


@pytest.fixture(scope="module")
def lorenz():
    t = np.arange(0, 4, 0.002)
    return lorenz_run(t), t


fd_model = pysindy_defaults


# ---------------------------------------------------------------- 1. short records
def test_short_records_fall_back_to_pysindys_derivatives_with_a_warning(short_lorenz):
    """12 samples: the default smoothing cannot be chosen, so finite differences are used
    (warned) and, with PySINDy's threshold, the coefficients are PySINDy's."""
    x, t = short_lorenz
    with pytest.warns(ShortRecordWarning, match="AutoSmoothing.*40 samples.*have 12"):
        ours = dc.DiscrepancyModel(optimizer=dc.STLSQ(threshold=0.1)).fit(x, t)
    assert isinstance(ours.differentiation_method_, dc.FiniteDifference)
    np.testing.assert_allclose(ours.coefficients(), ps.SINDy().fit(x, t).coefficients(), **TOL)


def test_the_automatic_threshold_on_a_short_record_is_chosen_by_bic(capsys):
    """PySINDy's 1-D test data (10 samples of x = 2t): both defaults fall back, with a
    warning each, and find x' = 2 as PySINDy does."""
    t = np.linspace(0, 1, 10)
    x = 2 * t[:, None]
    with pytest.warns(ShortRecordWarning) as caught:
        ours = dc.DiscrepancyModel().fit(x, t)
    assert {str(w.message).split(" ")[0] for w in caught} == {"AutoSmoothing", "threshold='auto'"}
    np.testing.assert_allclose(ours.coefficients(), ps.SINDy().fit(x, t).coefficients(), **TOL)
    ours.print()
    assert "short-record fallback (10 samples" in capsys.readouterr().out


# ---------------------------------------------------------------- sample weights
@pytest.mark.parametrize("make", [lambda: (ps.STLSQ(threshold=0.2), dc.STLSQ(threshold=0.2)),
                                  lambda: (ps.SR3(reg_weight_lam=0.05), dc.SR3(0.05)),
                                  lambda: (ps.STLSQ(threshold=0.2, normalize_columns=True),
                                           dc.STLSQ(threshold=0.2, normalize_columns=True))],
                         ids=["stlsq", "sr3", "stlsq-normalized"])
def test_optimizer_fit_takes_sample_weight(make, rng):
    theta = rng.normal(size=(300, 6))
    y = theta @ rng.normal(size=(6, 2)) + 0.1 * rng.normal(size=(300, 2))
    w = rng.uniform(0.1, 3, 300)
    peer, ours = make()
    np.testing.assert_allclose(ours.fit(theta, y, sample_weight=w).coef_,
                               peer.fit(theta, y, sample_weight=w).coef_, **TOL)
    # a weight of 2 is the row given twice (an independent check of the weighting)
    twice = np.r_[theta, theta[:50]], np.r_[y, y[:50]]
    weights = np.r_[np.full(50, 2.0), np.ones(250)]
    _, again = make()
    np.testing.assert_allclose(again.fit(theta, y, sample_weight=weights).coef_,
                               make()[1].fit(*twice).coef_, rtol=1e-10, atol=1e-12)


# ---------------------------------------------------------------- 2. the traps
def test_coefficients_are_live_as_in_pysindy(lorenz):
    x, t = lorenz
    peer, ours = ps.SINDy().fit(x, t), fd_model().fit(x, t)
    for model in (peer, ours):
        model.coefficients()[0, 1] += 0.5       # an edit in place
    np.testing.assert_allclose(ours.predict(x), peer.predict(x), **TOL)
    np.testing.assert_allclose(ours.simulate(x[0], t[:101], rtol=1e-12, atol=1e-12),
                               peer.simulate(x[0], t[:101]), **TOL)   # 0.2 time units
    assert ours.equations()[0].startswith(f"{peer.coefficients()[0, 1]:.3f} x1")


@pytest.mark.parametrize("t_kind", ["step", "times"])
def test_a_models_differentiation_method_returns_x_dot_like_pysindys(lorenz, t_kind):
    x, t = lorenz
    t = t[1] - t[0] if t_kind == "step" else t
    ours = dc.FiniteDifference()(x, t)
    np.testing.assert_allclose(ours, ps.FiniteDifference()(x, t), **TOL)
    # the feature-overview residual of PySINDy's examples: x_dot - predict broadcasts right
    model = fd_model().fit(x, t)
    residual = model.differentiation_method(x, t) - model.predict(x)
    assert residual.shape == x.shape and np.abs(residual).max() < 1e-3 * np.abs(ours).max()
    smoothed = dc.SavitzkyGolay(11, 3)
    smoothed(x, t)
    assert smoothed.smoothed_x_.shape == x.shape


def test_discrete_simulate_stops_like_pysindy_and_refuses_unknown_keywords():
    x = np.zeros(100)
    x[0] = 0.5
    for k in range(99):
        x[k + 1] = 3.6 * x[k] * (1 - x[k])
    peer = ps.DiscreteSINDy().fit(x, t=1)
    ours = dc.DiscrepancyModel(discrete_time=True, optimizer=dc.STLSQ(threshold=0.1)).fit(x)
    np.testing.assert_allclose(ours.coefficients(), peer.coefficients(), **TOL)
    def stop(state):
        return state[0] > 0.89
    np.testing.assert_allclose(ours.simulate([0.5], 50, stop_condition=stop),
                               peer.simulate(np.array([0.5]), 50, stop_condition=stop), **TOL)
    for bad in ({"rtoll": 1e-9}, {"integrator_kws": {"rtol": 1e-9}}):
        with pytest.raises(ParameterError, match="discrete-time model takes"):
            ours.simulate([0.5], 10, **bad)


def test_feature_ordered_constraints_mean_the_same_as_target_ordered(lorenz):
    """The same rule (coefficient of x in x' equals -10, of y in z' equals 0) written in
    both of PySINDy's orders gives the same model, equal to PySINDy's ConstrainedSR3."""
    x, t = lorenz
    n, p = 3, 10
    target = np.zeros((2, n * p))
    target[0, 0 * p + 1], target[1, 2 * p + 2] = 1.0, 1.0
    feature = target.reshape(2, n, p).transpose(0, 2, 1).reshape(2, n * p)
    rhs = np.array([-10.0, 0.0])
    a = fd_model(optimizer=dc.STLSQ(threshold=0.1, constraints=dc.LinearConstraints(
        n, p, eq_lhs=target, eq_rhs=rhs))).fit(x, t)
    b = fd_model(optimizer=dc.STLSQ(threshold=0.1, constraints=dc.LinearConstraints(
        n, p, eq_lhs=feature, eq_rhs=rhs, order="feature"))).fit(x, t)
    np.testing.assert_allclose(a.coefficients(), b.coefficients(), rtol=1e-12, atol=1e-12)
    assert a.coefficients()[0, 1] == pytest.approx(-10.0, rel=1e-10)
    pytest.importorskip("cvxpy")          # PySINDy's ConstrainedSR3 needs it to import
    kw = dict(reg_weight_lam=0.05, constraint_rhs=rhs, equality_constraints=True)
    peer = ps.SINDy(optimizer=ps.ConstrainedSR3(constraint_lhs=feature, constraint_order="feature",
                                                **kw)).fit(x, t)
    for lhs, order in ((feature, "feature"), (target, "target")):
        ours = fd_model(optimizer=dc.ConstrainedSR3(constraint_lhs=lhs, constraint_order=order,
                                                    **kw)).fit(x, t)
        np.testing.assert_allclose(ours.coefficients(), peer.coefficients(), **TOL)


def test_names_start_at_x1_and_pysindys_zero_based_names_cannot_be_misread(lorenz):
    x, t = lorenz
    with pytest.raises(dc.errors.UnknownNameError, match="x0 is not a variable.*start at x1"):
        fd_model(constraints=dc.Constraints(exact_equations=["x0"])).fit(x, t)
    with pytest.warns(NameConventionWarning, match="x1 refer.*PySINDy"):
        fd_model(constraints=dc.Constraints(exact_equations=["x1"])).fit(x, t)
    with warnings.catch_warnings():
        warnings.simplefilter("error", NameConventionWarning)   # x3 is only ours: no warning
        fd_model(constraints=dc.Constraints(exact_equations=["x3"])).fit(x, t)
        named = fd_model(constraints=dc.Constraints(exact_equations=["x1"])).fit(
            x, t, feature_names=["x0", "x1", "x2"])
    peer = ps.SINDy().fit(x, t)
    assert named.get_feature_names() == peer.get_feature_names()
    assert not named.coefficients()[1].any()          # PySINDy's x1: the second equation
    np.testing.assert_allclose(named.coefficients()[[0, 2]], peer.coefficients()[[0, 2]], **TOL)


# ---------------------------------------------------------------- 3. ensembles
@pytest.mark.parametrize("kw", [dict(bagging=True), dict(library_ensemble=True),
                                dict(bagging=True, library_ensemble=True, n_candidates_to_drop=2),
                                dict(bagging=True, replace=False, n_models=7),
                                dict(bagging=True, n_subset=400,
                                     ensemble_aggregator=lambda c: np.mean(c, axis=0))],
                         ids=["bagging", "library", "both", "no-replace", "mean"])
def test_ensembles_equal_pysindys_from_the_same_draws(lorenz, kw):
    x, t = lorenz
    x = x + 0.01 * np.random.default_rng(0).normal(size=x.shape)
    kw = {"n_models": 5, **kw}
    np.random.seed(7)  # noqa: NPY002  (PySINDy draws from the global generator)
    peer = ps.SINDy(optimizer=ps.EnsembleOptimizer(ps.STLSQ(threshold=0.1), **kw)).fit(x, t)
    np.random.seed(7)  # noqa: NPY002  (PySINDy draws from the global generator)
    ours = fd_model(optimizer=dc.EnsembleOptimizer(dc.STLSQ(threshold=0.1), **kw)).fit(x, t)
    np.testing.assert_allclose(ours.coefficients(), peer.coefficients(), **TOL)
    np.testing.assert_allclose(ours.optimizer_.coef_list, np.array(peer.optimizer.coef_list),
                               **TOL)
    assert np.array_equal(ours.optimizer_.inclusion_probability_,
                          np.mean(np.array(peer.optimizer.coef_list) != 0, axis=0))
    # 0.1 time units: PySINDy's simulate (its library rebuilt per step) is most of the test
    np.testing.assert_allclose(ours.simulate(x[0], t[:51], rtol=1e-12, atol=1e-12),
                               peer.simulate(x[0], t[:51]), **TOL)
    seeded = fd_model(optimizer=dc.EnsembleOptimizer(dc.STLSQ(threshold=0.1), random_state=7,
                                                     **kw)).fit(x, t)
    np.testing.assert_array_equal(seeded.coefficients(), ours.coefficients())


def test_an_ensemble_gives_the_bootstraps_table_and_intervals(lorenz):
    from discrepancy.models.core.uncertainty import CoefficientUncertainty

    x, t = lorenz
    x = x + 0.05 * np.random.default_rng(3).normal(size=x.shape)
    model = fd_model(optimizer=dc.EnsembleOptimizer(dc.STLSQ(threshold=0.1), bagging=True,
                                                    n_models=12, random_state=0)).fit(x, t)
    spread = CoefficientUncertainty.from_ensemble(model)
    np.testing.assert_array_equal(spread.inclusion_probability,
                                  model.optimizer_.inclusion_probability_)
    low, high = spread.interval()
    assert np.all(low <= model.coefficients()) and np.all(model.coefficients() <= high)
    assert "±" in model.equations(uncertainty=spread)[0]
    with pytest.raises(ParameterError, match="needs a model fitted with an EnsembleOptimizer"):
        CoefficientUncertainty.from_ensemble(fd_model().fit(x, t))


def test_library_ensembles_stream(lorenz):
    """Dropping terms needs only the Gram statistics: a chunked fit equals the in-memory
    one; bagging samples needs the samples and says so."""
    x, t = lorenz
    opt = dc.EnsembleOptimizer(dc.STLSQ(threshold=0.1), library_ensemble=True, random_state=1)
    whole = fd_model(optimizer=opt).fit(x, t)
    chunks = (dc.Chunk(x[i:i + 700]) for i in range(0, len(x), 700))
    streamed = fd_model(optimizer=opt).fit(chunks, t[1] - t[0])
    np.testing.assert_allclose(streamed.coefficients(), whole.coefficients(), rtol=1e-9)
    bag = dc.EnsembleOptimizer(dc.STLSQ(threshold=0.1), bagging=True)
    with pytest.raises(ParameterError, match="needs the samples themselves"):
        fd_model(optimizer=bag).fit((dc.Chunk(x[i:i + 700]) for i in range(0, len(x), 700)),
                                    t[1] - t[0])


# ---------------------------------------------------------------- SR3 and ConstrainedSR3
@pytest.mark.parametrize("kw", [dict(regularizer="weighted_l0"), dict(regularizer="weighted_l1"),
                                dict(regularizer="weighted_l2"),
                                dict(reg_weight_lam=0.1, trimming_fraction=0.05),
                                dict(reg_weight_lam=0.1, regularizer="l1", trimming_fraction=0.1,
                                     trimming_step_size=0.5, max_iter=60),
                                dict(reg_weight_lam=0.1, initial_guess="ones")],
                         ids=["w-l0", "w-l1", "w-l2", "trim", "trim-l1", "guess"])
def test_sr3_per_term_weights_trimming_and_initial_guess_equal_pysindys(lorenz, kw):
    x, t = lorenz
    x = x.copy()
    x[::97] += 3.0                                           # outliers for the trimming
    kw = dict(kw)
    if kw.get("regularizer", "").startswith("weighted"):
        kw["reg_weight_lam"] = np.linspace(0.01, 0.3, 30).reshape(3, 10)
    if kw.get("initial_guess") == "ones":
        kw["initial_guess"] = np.ones((3, 10))
    peer = quiet(ps.SINDy(optimizer=ps.SR3(**kw)).fit, x, t)
    ours = quiet(fd_model(optimizer=dc.SR3(**kw)).fit, x, t)
    np.testing.assert_allclose(ours.coefficients(), peer.coefficients(), **TOL)
    if "trimming_fraction" in kw:
        np.testing.assert_allclose(ours.optimizer_.trimming_array, peer.optimizer.trimming_array,
                                   rtol=1e-8, atol=1e-10)
        assert ours.optimizer_.trimming_array[::97].mean() < 0.5   # outliers lost weight


@pytest.mark.parametrize("regularizer", ["l1", "weighted_l1", "l2"])
def test_inequality_constrained_sr3_is_the_exact_optimum(rng, regularizer):
    """No PySINDy to 1e-8 here (its CVXPY stops at its tolerance): the answer satisfies the
    KKT conditions of min |y - Θξ|² + λ R(ξ) s.t. Cξ <= d to rounding, and PySINDy's (with
    CVXPY installed and enough iterations) is within its solver's accuracy of it."""
    theta = rng.normal(size=(200, 5))
    y = theta @ np.array([[1.0, 0.5], [0, -2], [0.3, 0], [0, 0], [2, 1]]) + \
        0.05 * rng.normal(size=(200, 2))
    lhs = np.zeros((2, 10))
    lhs[0, 4], lhs[1, 5 + 1] = 1.0, -1.0                     # ξ[0,4] <= 1.5, ξ[1,1] >= -1
    rhs = np.array([1.5, 1.0])
    lam = 2.0 if regularizer != "weighted_l1" else np.full((2, 5), 2.0)
    kw = dict(reg_weight_lam=lam, regularizer=regularizer, constraint_lhs=lhs,
              constraint_rhs=rhs, inequality_constraints=True)
    coef = dc.ConstrainedSR3(**kw).fit(theta, y).coef_
    xi = coef.ravel()
    assert np.all(lhs @ xi <= rhs + 1e-12) and np.any(np.abs(lhs @ xi - rhs) < 1e-10)
    # stationarity: ∇|y - Θξ|² + λ ∂R + Cᵀμ ∋ 0 with μ >= 0 on the active rows
    grad = (2 * (theta.T @ (theta @ coef.T - y))).T.ravel()
    active = np.abs(lhs @ xi - rhs) < 1e-10
    mu = np.linalg.lstsq(lhs[active].T, -(grad + (2 * xi * 2.0 if regularizer == "l2"
                                                  else 2.0 * np.sign(xi)))[:, None],
                         rcond=None)[0].ravel()
    assert np.all(mu >= -1e-8)
    residual = grad + lhs[active].T @ mu
    if regularizer == "l2":
        np.testing.assert_allclose(residual + 4.0 * xi, 0, atol=1e-7)
    else:
        on = xi != 0
        np.testing.assert_allclose(residual[on] + 2.0 * np.sign(xi[on]), 0, atol=1e-7)
        assert np.all(np.abs(residual[~on]) <= 2.0 + 1e-7)
    pytest.importorskip("cvxpy")
    # PySINDy hands max_iter (30 by default) to CVXPY's solver, which then may stop before
    # the constraints hold; given iterations enough it agrees to its solver's accuracy
    peer = ps.ConstrainedSR3(max_iter=1000, tol=1e-10, **kw).fit(theta, y).coef_
    np.testing.assert_allclose(coef, peer, atol=1e-5)


# ---------------------------------------------------------------- FiniteDifference options
@pytest.mark.parametrize("kw", [dict(order=1), dict(order=3), dict(order=4), dict(order=6, d=2),
                                dict(d=2), dict(d=3, order=2), dict(drop_endpoints=True),
                                dict(order=4, periodic=True), dict(order=3, drop_endpoints=True)],
                         ids=lambda kw: "-".join(f"{k}{v}" for k, v in kw.items()))
@pytest.mark.parametrize("uniform", [True, False], ids=["uniform", "nonuniform"])
def test_finite_difference_options_equal_pysindys(kw, uniform, rng):
    t = np.linspace(0, 2 * np.pi, 60) if uniform else np.sort(rng.uniform(0, 2 * np.pi, 60))
    if kw.get("periodic") and not uniform:
        pytest.skip("PySINDy's periodic stencils assume uniform steps at the wrap")
    x = np.c_[np.sin(2 * t), np.cos(t) + 0.1 * t]
    ours = dc.FiniteDifference(**kw)(x, t)
    peer = ps.FiniteDifference(**kw)._differentiate(x, t)
    assert np.array_equal(np.isnan(ours), np.isnan(peer))
    np.testing.assert_allclose(ours[~np.isnan(ours)], peer[~np.isnan(peer)], **TOL)


def test_dropped_endpoints_leave_the_fit_as_in_pysindy(lorenz):
    x, t = lorenz
    kw = dict(order=4, drop_endpoints=True)
    peer = ps.SINDy(differentiation_method=ps.FiniteDifference(**kw)).fit(x, t)
    ours = fd_model(differentiation_method=dc.FiniteDifference(**kw)).fit(x, t)
    np.testing.assert_allclose(ours.coefficients(), peer.coefficients(), **TOL)
    assert ours.statistics_.count == len(x) - 4
    with pytest.raises(ParameterError, match="periodic=True needs an even order"):
        dc.FiniteDifference(order=3, periodic=True)(x, t)


# ---------------------------------------------------------------- model options
def test_simulate_takes_pysindys_integrator_and_integrator_kws(lorenz):
    x, t = lorenz
    peer, ours = ps.SINDy().fit(x, t), fd_model().fit(x, t)
    tt = t[:101]    # 0.2 time units: PySINDy's simulate (slow per step) is most of the test
    np.testing.assert_allclose(ours.simulate(x[0], tt, integrator="solve_ivp"),
                               peer.simulate(x[0], tt), **TOL)
    np.testing.assert_allclose(ours.simulate(x[0], tt, integrator="odeint"),
                               peer.simulate(x[0], tt, integrator="odeint"), rtol=1e-6)
    kws = {"method": "DOP853", "rtol": 1e-11, "atol": 1e-11}
    np.testing.assert_allclose(ours.simulate(x[0], tt, integrator_kws=kws),
                               peer.simulate(x[0], tt, integrator_kws=kws), **TOL)
    with pytest.raises(ParameterError, match="integrator must be one of"):
        ours.simulate(x[0], tt, integrator="euler")
    with pytest.raises(ParameterError, match="both in integrator_kws and as keywords"):
        ours.simulate(x[0], tt, integrator_kws={"rtol": 1e-9}, rtol=1e-9)


def test_score_passes_metric_kws_like_pysindy(lorenz):
    x, t = lorenz
    peer, ours = ps.SINDy().fit(x, t), fd_model().fit(x, t)
    np.testing.assert_allclose(ours.score(x, t, multioutput="raw_values"),
                               peer.score(x, t, multioutput="raw_values"), rtol=1e-10)
    w = np.linspace(0.5, 2, len(x))
    assert ours.score(x, t, metric=mean_squared_error, sample_weight=w) == pytest.approx(
        peer.score(x, t, metric=mean_squared_error, sample_weight=w), rel=1e-9)
    assert ours.score(x, t) == pytest.approx(peer.score(x, t, metric=r2_score), rel=1e-10)


def test_u_given_as_one_number_is_a_constant_input(lorenz):
    x, t = lorenz
    x = x[:800]
    peer = ps.SINDy(feature_library=ps.PolynomialLibrary(degree=1, include_bias=False)).fit(
        x, t[:800], u=2.0)
    ours = fd_model(feature_library=dc.PolynomialLibrary(1, include_bias=False)).fit(
        x, t[:800], u=2.0)
    np.testing.assert_allclose(ours.coefficients(), peer.coefficients(), **TOL)
    np.testing.assert_allclose(ours.predict(x, u=2.0), peer.predict(x, u=2.0), **TOL)


@pytest.mark.parametrize("regressor", [lambda: Lasso(alpha=0.05, fit_intercept=False),
                                       lambda: ElasticNet(alpha=0.05, fit_intercept=False)],
                         ids=["lasso", "elasticnet"])
def test_scikit_learn_regressors_as_optimizers(lorenz, regressor):
    x, t = lorenz
    peer = quiet(ps.SINDy(optimizer=regressor()).fit, x, t)
    ours = quiet(fd_model(optimizer=regressor()).fit, x, t)
    np.testing.assert_allclose(ours.coefficients(), peer.coefficients(), rtol=1e-7, atol=1e-9)
    peer = quiet(ps.SINDy(optimizer=ps.WrappedOptimizer(regressor())).fit, x, t)
    ours = quiet(fd_model(optimizer=dc.optimizers.WrappedOptimizer(regressor())).fit, x, t)
    np.testing.assert_allclose(ours.coefficients(), peer.coefficients(), rtol=1e-7, atol=1e-9)
