"""Adversarial rows for PySINDy's options (issue 23): sample weights, SR3's per-term weights
and trimming, ConstrainedSR3, EnsembleOptimizer, wrapped scikit-learn regressors, the
FiniteDifference options, t required, feature_names, the integrator keywords, discrete
stop conditions and metric options."""
from __future__ import annotations

import numpy as np
from sklearn.linear_model import Lasso, LinearRegression

import discrepancy as dc
from adversarial import Case, check, circle, fast, params, raises, returns
from discrepancy.errors import DataError, ParameterError, ShapeError, UnknownNameError

RNG = np.random.default_rng(2)
THETA = RNG.normal(size=(120, 3))
Y = THETA @ np.array([[1.0], [0.0], [-2.0]])
T, X, XD = circle(200)
ROT = fast().fit(X, 0.01, x_dot=XD)
MAP = fast(discrete_time=True, feature_library=dc.PolynomialLibrary(1)).fit(
    0.9 ** np.arange(50.0)[:, None])
TS = np.linspace(0, 1, 11)
G, B = THETA.T @ THETA, THETA.T @ Y


def exact(expected, atol=1e-9):
    return lambda value: np.allclose(value, expected, atol=atol)


def lstsq():
    return np.linalg.lstsq(THETA, Y, rcond=None)[0].T


def csr3(**kw):
    lhs = np.zeros((1, 3))
    lhs[0, 1] = 1.0
    base = dict(constraint_lhs=lhs, constraint_rhs=np.array([0.5]), equality_constraints=True)
    return dc.ConstrainedSR3(**{**base, **kw}).fit(THETA, Y)


def ensemble(**kw):
    return dc.EnsembleOptimizer(dc.STLSQ(threshold=0.1), **kw).fit(THETA, Y)


CASES = [
    # --- sample weights
    Case("optimizer", "sample_weight negative", lambda: dc.STLSQ(0.1).fit(THETA, Y, sample_weight=-np.ones(120)), raises(DataError, r"sample_weight must be >= 0")),
    Case("optimizer", "sample_weight of the wrong length", lambda: dc.STLSQ(0.1).fit(THETA, Y, sample_weight=np.ones(7)), raises(ShapeError, r"sample_weight")),
    Case("optimizer", "sample_weight all zero", lambda: dc.STLSQ(0.1).fit(THETA, Y, sample_weight=np.zeros(120)), raises(DataError, r"at least one positive weight")),
    Case("optimizer", "sample_weight one number", lambda: dc.STLSQ(0.1).fit(THETA, Y, sample_weight=3.0).coef_, returns(exact(lstsq()))),
    # --- SR3 per-term weights and trimming
    Case("optimizer", "SR3 weighted regularizer with one number", lambda: dc.SR3(0.1, "weighted_l0").fit(THETA, Y), raises(ParameterError, r"weighted_l0.*needs reg_weight_lam as an array")),
    Case("optimizer", "SR3 per-term weights of the wrong shape", lambda: dc.SR3(np.ones((2, 2)), "weighted_l1").fit(THETA, Y), raises(ShapeError, r"reg_weight_lam must be \(n_targets, n_features\) = \(1, 3\)")),
    Case("optimizer", "SR3 negative per-term weight", lambda: dc.SR3(-np.ones((1, 3)), "weighted_l1").fit(THETA, Y), raises(ParameterError, r"reg_weight_lam must be")),
    Case("optimizer", "SR3 zero per-term weights are least squares", lambda: dc.SR3(np.zeros((1, 3)), "weighted_l0").fit(THETA, Y).coef_, returns(exact(lstsq()))),
    Case("optimizer", "SR3 trimming everything", lambda: dc.SR3(trimming_fraction=1.0).fit(THETA, Y), raises(ParameterError, r"trimming_fraction must be")),
    Case("optimizer", "SR3 trimming with unbias", lambda: dc.SR3(trimming_fraction=0.1, unbias=True).fit(THETA, Y), raises(ParameterError, r"unbias=True would undo the trimming")),
    Case("optimizer", "SR3 trimming from Gram statistics", lambda: dc.SR3(trimming_fraction=0.1).fit_gram(G, B), raises(ParameterError, r"needs the samples themselves \(trimming")),
    Case("optimizer", "SR3 initial guess of the wrong shape", lambda: dc.SR3(initial_guess=np.ones((2, 2))).fit(THETA, Y), raises(ShapeError, r"initial_guess must be \(n_targets, n_features\)")),
    # --- ConstrainedSR3
    Case("optimizer", "ConstrainedSR3 lhs without rhs", lambda: dc.ConstrainedSR3(constraint_lhs=np.ones((1, 3))).fit(THETA, Y), raises(ParameterError, r"constraint_lhs and constraint_rhs together")),
    Case("optimizer", "ConstrainedSR3 lhs of the wrong width", lambda: csr3(constraint_lhs=np.ones((1, 4))), raises(ShapeError, r"constraint_lhs must have n_targets \* n_features = 3")),
    Case("optimizer", "ConstrainedSR3 rows of lhs and rhs differ", lambda: csr3(constraint_rhs=np.ones(2)), raises(ShapeError, r"constraint_lhs has 1 rows, constraint_rhs 2")),
    Case("optimizer", "ConstrainedSR3 inequality with l0", lambda: csr3(inequality_constraints=True, equality_constraints=False), raises(ParameterError, r"inequality constraints need a convex regularizer")),
    Case("optimizer", "ConstrainedSR3 both kinds without a separation", lambda: csr3(inequality_constraints=True, regularizer="l1"), raises(ParameterError, r"give constraint_separation_index")),
    Case("optimizer", "ConstrainedSR3 unknown order", lambda: csr3(constraint_order="rows"), raises(ParameterError, r"constraint_order must be one of")),
    Case("optimizer", "ConstrainedSR3 unbias with constraints", lambda: csr3(unbias=True), raises(ParameterError, r"unbias=True would break the constraints")),
    Case("optimizer", "ConstrainedSR3 equality holds with l0", lambda: csr3(reg_weight_lam=0.0).coef_[0, 1], returns(lambda v: abs(v - 0.5) < 1e-9)),
    Case("optimizer", "ConstrainedSR3 inequality at its bound", lambda: csr3(regularizer="l1", reg_weight_lam=1e-3, inequality_constraints=True, equality_constraints=False, constraint_rhs=np.array([-0.25])).coef_[0, 1], returns(lambda v: abs(v + 0.25) < 1e-9)),
    Case("optimizer", "LinearConstraints of an unknown order", lambda: dc.LinearConstraints(1, 3, order="rows"), raises(ParameterError, r"order must be 'target' or 'feature'")),
    # --- EnsembleOptimizer
    Case("optimizer", "ensemble of nothing", lambda: ensemble(), raises(ParameterError, r"set bagging=True and/or library_ensemble=True")),
    Case("optimizer", "ensemble of 0 models", lambda: ensemble(bagging=True, n_models=0), raises(ParameterError, r"n_models must be")),
    Case("optimizer", "ensemble aggregator of the wrong shape", lambda: ensemble(bagging=True, ensemble_aggregator=lambda c: np.zeros(2)), raises(ShapeError, r"ensemble_aggregator must return an array \(1, 3\)")),
    Case("optimizer", "ensemble aggregator that raises", lambda: ensemble(bagging=True, ensemble_aggregator=lambda c: 1 / 0), raises(ParameterError, r"ensemble_aggregator raised ZeroDivisionError")),
    Case("optimizer", "ensemble dropping more terms than there are", lambda: ensemble(library_ensemble=True, n_candidates_to_drop=5, n_models=2).coef_, returns(exact(dc.STLSQ(threshold=0.1).fit(THETA, Y).coef_))),
    Case("optimizer", "ensemble bagging from Gram statistics", lambda: dc.EnsembleOptimizer(bagging=True).fit_gram(G, B), raises(ParameterError, r"needs the samples themselves \(bagging")),
    Case("optimizer", "ensemble of exact data is the exact model", lambda: ensemble(bagging=True, n_models=6, random_state=3).coef_, returns(exact([[1, 0, -2]]))),
    Case("optimizer", "ensemble with a random_state of text", lambda: ensemble(bagging=True, random_state="a"), raises(ParameterError, r"random_state must be")),
    # --- wrapped regressors
    Case("optimizer", "wrapped object that is not a regressor", lambda: dc.optimizers.WrappedOptimizer(42).fit(THETA, Y), raises(ParameterError, r"optimizer must be a scikit-learn regressor")),
    Case("optimizer", "wrapped regressor with an intercept", lambda: dc.optimizers.WrappedOptimizer(LinearRegression()).fit(THETA, Y + 1), raises(ParameterError, r"fit_intercept=False")),
    Case("optimizer", "wrapped least squares", lambda: dc.optimizers.WrappedOptimizer(LinearRegression(fit_intercept=False)).fit(THETA, Y).coef_, returns(exact(lstsq()))),
    Case("optimizer", "wrapped Lasso from Gram statistics", lambda: dc.optimizers.WrappedOptimizer(Lasso()).fit_gram(G, B), raises(ParameterError, r"needs the samples themselves \(a scikit-learn regressor")),
    # --- FiniteDifference options
    Case("differentiation", "second derivative of first order", lambda: dc.FiniteDifference(order=1, d=2)(X, T), raises(ParameterError, r"d=2 needs order >= 2")),
    Case("differentiation", "order 0", lambda: dc.FiniteDifference(order=0)(X, T), raises(ParameterError, r"order must be an integer >= 1")),
    Case("differentiation", "periodic with an odd order", lambda: dc.FiniteDifference(order=3, periodic=True)(X, T), raises(ParameterError, r"periodic=True needs an even order")),
    Case("differentiation", "fourth order exact on a quartic", lambda: dc.FiniteDifference(order=4)(T[:, None] ** 4, T), returns(exact(4 * T[:, None] ** 3, 1e-9))),
    Case("differentiation", "second derivative exact on a cubic", lambda: dc.FiniteDifference(d=2, order=2)(T[:, None] ** 3, T), returns(exact(6 * T[:, None], 1e-7))),
    Case("differentiation", "dropped endpoints are NaN", lambda: dc.FiniteDifference(order=4, drop_endpoints=True)(X, T), returns(lambda v: np.isnan(v[[0, 1, -2, -1]]).all() and np.isfinite(v[2:-2]).all())),
    Case("differentiation", "periodic derivative of a full sine period", lambda: dc.FiniteDifference(order=6, periodic=True)(np.sin(np.arange(64) * 2 * np.pi / 64)[:, None], np.arange(64) * 2 * np.pi / 64), returns(exact(np.cos(np.arange(64) * 2 * np.pi / 64)[:, None], 1e-6))),
    Case("stream", "dropped endpoints in a stream", lambda: fast(differentiation_method=dc.FiniteDifference(drop_endpoints=True)).fit(iter([dc.Chunk(X[:100]), dc.Chunk(X[100:])]), 0.01), raises(ParameterError, r"drops each trajectory's end rows")),
    # --- t required, names
    Case("fit", "no t for a continuous-time model", lambda: fast().fit(X), raises(ParameterError, r"fit: t is required")),
    Case("fit", "no t with x_dot", lambda: fast().fit(X, x_dot=XD).coef_, returns(exact(ROT.coef_))),
    Case("fit", "feature_names of the wrong length", lambda: fast().fit(X, 0.01, feature_names=["a"]), raises(ShapeError, r"feature_names must have 2 names")),
    Case("fit", "feature_names repeated", lambda: fast().fit(X, 0.01, feature_names=["a", "a"]), raises(ShapeError, r"feature_names must be distinct identifiers")),
    Case("fit", "feature_names of chunks", lambda: fast().fit(iter([dc.Chunk(X)]), 0.01, feature_names=["a", "b"]), raises(ParameterError, r"names as the model's state_names")),
    Case("fit", "a constraint on PySINDy's x0", lambda: fast(constraints=dc.Constraints(exact_equations=["x0"])).fit(X, 0.01), raises(UnknownNameError, r"x0 is not a variable: the default names here start at x1")),
    Case("fit", "u as one number", lambda: fast(feature_library=dc.PolynomialLibrary(1, include_bias=False)).fit(X, 0.01, u=1.0, x_dot=XD + 0.5).coef_, returns(exact([[0, 1, 0.5], [-1, 0, 0.5]]))),
    Case("score", "no t", lambda: ROT.score(X), raises(ParameterError, r"score: t is required")),
    Case("score", "options for rmse", lambda: ROT.score(X, 0.01, metric="rmse", squared=False), raises(ParameterError, r"metric='rmse' takes no options")),
    Case("score", "an option r2_score does not know", lambda: ROT.score(X, 0.01, bogus=1), raises(ParameterError, r"metric raised TypeError")),
    Case("score", "r2 per state", lambda: ROT.score(X, x_dot=XD, multioutput="raw_values"), returns(exact([1.0, 1.0]))),
    Case("model", "differentiate without t", lambda: ROT.differentiate(X), raises(ParameterError, r"differentiate: t is required")),
    Case("model", "predict_ahead without t", lambda: ROT.predict_ahead(X), raises(ParameterError, r"predict_ahead: t is required")),
    Case("bootstrap", "no t", lambda: ROT.bootstrap(X, n_resamples=5), raises(ParameterError, r"bootstrap: t is required")),
    # --- simulate keywords
    Case("simulate", "an unknown integrator", lambda: ROT.simulate([0, 1], TS, integrator="euler"), raises(ParameterError, r"integrator must be one of 'solve_ivp', 'odeint'")),
    Case("simulate", "integrator_kws not a dict", lambda: ROT.simulate([0, 1], TS, integrator_kws=1e-9), raises(ParameterError, r"integrator_kws must be a dict")),
    Case("simulate", "an option given twice", lambda: ROT.simulate([0, 1], TS, integrator_kws={"rtol": 1e-9}, rtol=1e-9), raises(ParameterError, r"both in integrator_kws and as keywords")),
    Case("simulate", "a typo inside integrator_kws", lambda: ROT.simulate([0, 1], TS, integrator_kws={"rtoll": 1e-9}), raises(ParameterError, r"unknown option\(s\) \['rtoll'\]")),
    Case("simulate", "odeint with a method", lambda: ROT.simulate([0, 1], TS, integrator="odeint", integrator_kws={"method": "RK45"}), raises(ParameterError, r"integrator='odeint' takes no method")),
    Case("simulate", "odeint on the rotation", lambda: ROT.simulate([0, 1], TS, integrator="odeint", integrator_kws={"rtol": 1e-11, "atol": 1e-11}), returns(exact(np.c_[np.sin(TS), np.cos(TS)], 1e-8))),
    Case("simulate", "interpolator that is not callable", lambda: fast(feature_library=dc.PolynomialLibrary(1)).fit(X, 0.01, u=X[:, :1]).simulate([0, 1], TS, u=np.zeros(11), interpolator="cubic"), raises(ParameterError, r"interpolator must be a callable")),
    Case("simulate", "stop_condition of a continuous model", lambda: ROT.simulate([0, 1], TS, stop_condition=lambda x: True), raises(ParameterError, r"stop_condition is for discrete-time models")),
    Case("simulate", "a map with an unknown keyword", lambda: MAP.simulate([1.0], 10, rtoll=1e-3), raises(ParameterError, r"discrete-time model takes x0, t \(steps\), u and stop_condition; got \['rtoll'\]")),
    Case("simulate", "a map's stop_condition not callable", lambda: MAP.simulate([1.0], 10, stop_condition=0.5), raises(ParameterError, r"stop_condition must be a callable")),
    Case("simulate", "a map stopped by its condition", lambda: MAP.simulate([1.0], 10, stop_condition=lambda x: x[0] < 0.75), returns(exact(0.9 ** np.arange(4.0)[:, None], 1e-9))),
]


@params(CASES)
def test_case(case):
    check(case)
