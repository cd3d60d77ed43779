"""A PySINDy user's calls, run side by side with PySINDy 2.x on identical input: the call shapes
it accepts (lists of trajectories, 1-D x, callable u returning (r,) or (1, r), given x_dot,
times per trajectory), discrete-time maps, spectral derivatives and scikit-learn's tools.
Coefficients, predictions and simulations agree to 1e-8."""
import warnings

import numpy as np
import pysindy as ps
import pytest
from sklearn.base import clone
from sklearn.model_selection import GridSearchCV, TimeSeriesSplit

import discrepancy as dc

warnings.filterwarnings("ignore", category=UserWarning, module="pysindy")
TOL = dict(rtol=1e-8, atol=1e-8)


def pair(degree=2, threshold=0.1, **ours):
    """The same model in both libraries (PySINDy's defaults: finite differences, STLSQ 0.1)."""
    peer = ps.SINDy(feature_library=ps.PolynomialLibrary(degree=degree),
                    optimizer=ps.STLSQ(threshold=threshold),
                    differentiation_method=ps.FiniteDifference())
    mine = dc.DiscrepancyModel(feature_library=dc.PolynomialLibrary(degree),
                               optimizer=dc.STLSQ(threshold=threshold),
                               differentiation_method=dc.FiniteDifference(), **ours)
    return peer, mine


def forced_oscillator(helpers, x0, t, u):
    return helpers.integrate(lambda x, uu: np.array([x[1], -x[0] - 0.2 * x[1] + uu[0]]), x0, t,
                             lambda tau: np.atleast_1d(u(tau)).ravel())


@pytest.fixture(scope="module")
def lorenz_runs(lorenz_data):
    x = lorenz_data.x
    return [x[:2000], x[2000:3500], x[3500:]], lorenz_data.dt


def test_list_of_trajectories_fit_predict_and_score(lorenz_runs):
    xs, dt = lorenz_runs
    peer, mine = pair()
    peer.fit(xs, t=dt)
    mine.fit(xs, t=dt)
    np.testing.assert_allclose(mine.coefficients(), peer.coefficients(), **TOL)
    for a, b in zip(mine.predict(xs), peer.predict(xs), strict=True):
        np.testing.assert_allclose(a, b, **TOL)
    assert mine.score(xs, t=dt) == pytest.approx(peer.score(xs, t=dt), rel=1e-10)


def test_times_given_per_trajectory(lorenz_runs):
    xs, dt = lorenz_runs
    ts = [np.arange(len(x)) * dt + 3.0 * k for k, x in enumerate(xs)]
    peer, mine = pair()
    peer.fit(xs, t=ts)
    mine.fit(xs, t=ts)
    np.testing.assert_allclose(mine.coefficients(), peer.coefficients(), **TOL)
    for a, b in zip(mine.predict(xs), peer.predict(xs), strict=True):
        np.testing.assert_allclose(a, b, **TOL)
    for x, tk in zip(xs, ts, strict=True):   # each trajectory simulated from its own start
        np.testing.assert_allclose(mine.simulate(x[0], tk[:200], rtol=1e-12, atol=1e-12),
                                   peer.simulate(x[0], tk[:200]), **TOL)


def test_one_dimensional_x_is_one_state():
    t = np.linspace(0, 5, 501)
    x = 2 * np.exp(-0.7 * t)                    # x' = -0.7 x
    peer, mine = pair(degree=1, threshold=0.01)
    peer.fit(x, t=t)
    mine.fit(x, t=t)
    np.testing.assert_allclose(mine.coefficients(), peer.coefficients(), **TOL)
    np.testing.assert_allclose(mine.predict(x), peer.predict(x), **TOL)
    np.testing.assert_allclose(mine.simulate([2.0], t, rtol=1e-12, atol=1e-12),
                               peer.simulate([2.0], t), **TOL)


def test_given_x_dot(lorenz_data):
    x, xd = lorenz_data.x, lorenz_data.x_dot
    peer, mine = pair()
    peer.fit(x, t=lorenz_data.dt, x_dot=xd)
    mine.fit(x, t=lorenz_data.dt, x_dot=xd)
    np.testing.assert_allclose(mine.coefficients(), peer.coefficients(), **TOL)
    np.testing.assert_allclose(mine.predict(x), peer.predict(x), **TOL)
    t = np.arange(200) * lorenz_data.dt
    np.testing.assert_allclose(mine.simulate(x[0], t, rtol=1e-12, atol=1e-12),
                               peer.simulate(x[0], t), **TOL)
    np.testing.assert_allclose(mine.coefficients()[0, 1:3], [-10, 10], rtol=1e-6)


@pytest.mark.parametrize("shape", ["(r,)", "(1, r)"])
def test_callable_input_of_either_shape_simulates_like_pysindy(helpers, shape):
    t = np.linspace(0, 10, 1001)
    u = (lambda tau: np.array([np.sin(2 * tau)])) if shape == "(r,)" else \
        (lambda tau: np.array([[np.sin(2 * tau)]]))
    x = forced_oscillator(helpers, [1.0, 0.0], t, u)
    samples = np.sin(2 * t)[:, None]
    peer, mine = pair(degree=1, threshold=0.05)
    peer.fit(x, t=t, u=samples)
    mine.fit(x, t=t, u=samples)
    np.testing.assert_allclose(mine.coefficients(), peer.coefficients(), **TOL)
    np.testing.assert_allclose(mine.predict(x, samples), peer.predict(x, u=samples), **TOL)
    ours = mine.simulate(x[0], t[:300], u=u, rtol=1e-12, atol=1e-12)
    theirs = peer.simulate(x[0], t[:300], u=u)
    np.testing.assert_allclose(ours, theirs, **TOL)


def test_a_positional_x_dot_is_refused_not_taken_as_u(lorenz_data):
    _, mine = pair()
    with pytest.raises(dc.errors.ParameterError,
                       match="PySINDy's order is fit\\(x, t, x_dot, u\\)"):
        mine.fit(lorenz_data.x, lorenz_data.dt, lorenz_data.x_dot)


def test_discrete_time_map_with_a_wrong_parameter():
    """The logistic-type map x[k+1] = r x (1 - x) + 0.1 sin(x) with prior r = 3.5 (truth 3.7):
    the discrepancy 0.2 x - 0.2 x^2 + 0.1 sin(x) is recovered within 1 %, and simulated as
    PySINDy simulates its discrete models."""
    def step(x, r):
        return r * x * (1 - x) + 0.1 * np.sin(x)
    x = np.empty(400)
    x[0] = 0.3
    for k in range(399):
        x[k + 1] = step(x[k], 3.7)
    model = dc.DiscrepancyModel(prior=lambda z, u=None: 3.5 * z * (1 - z),
                                feature_library=dc.PolynomialLibrary(2) + dc.FourierLibrary(1),
                                discrete_time=True)   # the automatic threshold
    model.fit(x[:, None])
    names = model.get_feature_names()
    found = {names[j]: c for j, c in enumerate(model.coef_[0]) if c != 0}
    assert set(found) == {"x1", "x1^2", "sin(x1)"}
    for term, value in {"x1": 0.2, "x1^2": -0.2, "sin(x1)": 0.1}.items():
        assert found[term] == pytest.approx(value, rel=0.01)
    sim = model.simulate([0.3], 15)  # a chaotic map: errors grow ~1.4x per step
    np.testing.assert_allclose(sim[:, 0], x[:15], rtol=1e-4)
    # PySINDy's DiscreteSINDy on the same map (a well-conditioned library: with sin and cos
    # next to 1 and x^2 the columns are nearly collinear and solvers differ by ~1e-8)
    peer = ps.DiscreteSINDy(feature_library=ps.PolynomialLibrary(degree=3),
                            optimizer=ps.STLSQ(threshold=0.01))
    peer.fit(x[:, None], t=1)
    peer_model = dc.DiscrepancyModel(feature_library=dc.PolynomialLibrary(3),
                                     optimizer=dc.STLSQ(threshold=0.01), discrete_time=True)
    np.testing.assert_allclose(peer_model.fit(x[:, None]).coefficients(), peer.coefficients(),
                               **TOL)


def test_spectral_derivative_equals_pysindys_and_the_truth():
    t = np.arange(256) * 2 * np.pi / 256
    x = np.c_[np.sin(3 * t), np.cos(5 * t) + 0.3 * np.sin(t)]
    exact = np.c_[3 * np.cos(3 * t), -5 * np.sin(5 * t) + 0.3 * np.cos(t)]
    ours = dc.Spectral()(x, t)
    np.testing.assert_allclose(ours, exact, atol=1e-10)
    np.testing.assert_allclose(ours, ps.SpectralDerivative()._differentiate(x, t), atol=1e-10)


@pytest.mark.parametrize("times", ["step", "array"])
def test_grid_search_carries_t_to_every_fold_with_metadata_routing(lorenz_data, times):
    """With routing, every fold is fitted and scored with the real step (a times array is
    split like x): the search's scores equal a hand-written loop over the same splits."""
    import sklearn

    x, dt = lorenz_data.x, lorenz_data.dt
    t = dt if times == "step" else lorenz_data.t
    model = dc.DiscrepancyModel(feature_library=dc.PolynomialLibrary(2),
                                optimizer=dc.STLSQ(threshold=0.1),
                                differentiation_method=dc.FiniteDifference())
    grid, splits = [0.1, 5.0, 50.0], TimeSeriesSplit(n_splits=3)
    with sklearn.config_context(enable_metadata_routing=True), warnings.catch_warnings():
        warnings.simplefilter("ignore")      # threshold 50 removes every term (warned)
        search = GridSearchCV(model, {"optimizer__threshold": grid}, cv=splits).fit(x, t=t)
        by_hand = [np.mean([clone(model).set_params(optimizer__threshold=g).fit(
            x[a], t=t if times == "step" else t[a]).score(x[b], t=t if times == "step" else t[b])
            for a, b in splits.split(x)]) for g in grid]
    np.testing.assert_allclose(search.cv_results_["mean_test_score"], by_hand, rtol=1e-12)
    assert search.best_params_["optimizer__threshold"] == 0.1 and search.best_score_ > 0.999
    assert clone(model).get_params()["optimizer__threshold"] == 0.1


def test_without_routing_a_fold_scored_without_t_fails_loudly(lorenz_data):
    """scikit-learn without routing gives score no t: that is an error (reported as failed
    scores), never a score with a step of 1; PySINDy 2.1's search fails too."""
    model = dc.DiscrepancyModel(optimizer=dc.STLSQ(threshold=0.1),
                                differentiation_method=dc.FiniteDifference())
    search = GridSearchCV(model, {"optimizer__threshold": [0.1, 1.0]},
                          cv=TimeSeriesSplit(n_splits=2), error_score="raise")
    with pytest.raises(dc.errors.ParameterError, match="score: t is required.*routing"):
        search.fit(lorenz_data.x, t=lorenz_data.dt)
    with pytest.raises(dc.errors.ParameterError, match="fit: t is required"):
        model.fit(lorenz_data.x)
    with pytest.raises(TypeError):           # PySINDy: t is a required argument
        ps.SINDy().fit(lorenz_data.x)


def test_include_interaction_false_and_complexity(lorenz_data):
    x = lorenz_data.x
    peer = ps.SINDy(feature_library=ps.PolynomialLibrary(degree=3, include_interaction=False),
                    optimizer=ps.STLSQ(threshold=0.5))
    mine = dc.DiscrepancyModel(feature_library=dc.PolynomialLibrary(3, include_interaction=False),
                               optimizer=dc.STLSQ(threshold=0.5),
                               differentiation_method=dc.FiniteDifference())
    peer.fit(x, t=lorenz_data.dt)
    mine.fit(x, t=lorenz_data.dt)
    np.testing.assert_allclose(mine.coefficients(), peer.coefficients(), **TOL)
    assert mine.complexity == peer.complexity


def test_score_with_a_metric_function(lorenz_data):
    from sklearn.metrics import mean_absolute_error

    peer, mine = pair()
    peer.fit(lorenz_data.x, t=lorenz_data.dt)
    mine.fit(lorenz_data.x, t=lorenz_data.dt)
    ours = mine.score(lorenz_data.x, t=lorenz_data.dt, metric=mean_absolute_error)
    theirs = peer.score(lorenz_data.x, t=lorenz_data.dt, metric=mean_absolute_error)
    assert ours == pytest.approx(theirs, rel=1e-9)


def test_print_with_other_left_hand_sides(lorenz_data, capsys):
    _, mine = pair()
    mine.fit(lorenz_data.x, t=lorenz_data.dt)
    mine.print(lhs=["dx/dt", "dy/dt", "dz/dt"])
    lines = capsys.readouterr().out.splitlines()
    assert [line.split(" = ")[0] for line in lines[:3]] == ["dx/dt", "dy/dt", "dz/dt"]


@pytest.mark.parametrize("options", [dict(reg_weight_lam=0.1), dict(reg_weight_lam=0.5,
                                     regularizer="l1"),
                                     dict(reg_weight_lam=0.01, regularizer="l2",
                                          relax_coeff_nu=0.5),
                                     dict(reg_weight_lam=0.05, normalize_columns=True),
                                     dict(reg_weight_lam=0.1, unbias=True)])
def test_sr3_equals_pysindy(lorenz_data, options):
    x, dt = lorenz_data.x, lorenz_data.dt
    peer = ps.SINDy(optimizer=ps.SR3(**options), differentiation_method=ps.FiniteDifference())
    mine = dc.DiscrepancyModel(optimizer=dc.SR3(**options),
                               differentiation_method=dc.FiniteDifference())
    peer.fit(x, t=dt)
    mine.fit(x, t=dt)
    np.testing.assert_allclose(mine.coefficients(), peer.coefficients(), **TOL)


def test_differentiate_equals_pysindy(lorenz_runs):
    xs, dt = lorenz_runs
    _, mine = pair()
    np.testing.assert_allclose(mine.differentiate(xs[0], dt),
                               ps.FiniteDifference()(xs[0], dt), **TOL)
    assert [d.shape for d in mine.differentiate(xs, dt)] == [x.shape for x in xs]


def test_discrete_successors_given_as_x_dot():
    """Successors given as x_dot (PySINDy 1's fit(x[:-1], x_dot=x[1:]); DiscreteSINDy's
    x_next) are the targets (they were ignored before), so scoring x as its own successor
    is poor."""
    x = np.empty((200, 1))
    x[0] = 0.4
    for k in range(199):
        x[k + 1] = 3.6 * x[k] * (1 - x[k])
    peer = ps.DiscreteSINDy(optimizer=ps.STLSQ(threshold=0.01))
    mine = dc.DiscrepancyModel(discrete_time=True, optimizer=dc.STLSQ(threshold=0.01))
    peer.fit(x[:-1], t=1, x_next=x[1:])
    mine.fit(x[:-1], x_dot=x[1:])
    np.testing.assert_allclose(mine.coefficients(), peer.coefficients(), **TOL)
    np.testing.assert_allclose(mine.coefficients()[0, 1:], [3.6, -3.6], rtol=1e-10)
    assert mine.score(x, x_dot=x) == pytest.approx(peer.score(x, t=1, x_next=x), rel=1e-8)
    assert mine.score(x, x_dot=x) < 0.5


def test_stlsq_that_runs_out_of_iterations_warns_like_pysindy(lorenz_data):
    with pytest.warns(dc.errors.ConvergenceWarning, match="did not converge"):
        dc.DiscrepancyModel(optimizer=dc.STLSQ(threshold=0.1, max_iter=1)).fit(
            lorenz_data.x, t=lorenz_data.dt)
