"""A sample of PySINDy's own tests and documented examples, ported to this API.

Each case runs PySINDy's call on PySINDy's data (its test fixtures: 10 samples of ``x = 2t``,
12 samples of Lorenz, three Lorenz runs, the logistic map; its docstring examples) and ours
beside it. A case id starts with ``same`` (the same numbers to 1e-8, the same outcome for a
refused input) or ``documented`` (our behaviour differs as the guide's "Coming from PySINDy"
page, docs/guide/pysindy.md, says; the case checks the documented behaviour and that the page
says it).
``python -m pytest tests/test_pysindy_ported.py -q --collect-only`` lists the tally.
"""
import warnings
from pathlib import Path

import numpy as np
import pysindy as ps
import pytest
import sklearn
from scipy.integrate import odeint, solve_ivp
from sklearn.exceptions import ConvergenceWarning as SklearnConvergenceWarning
from sklearn.linear_model import ElasticNet, Lasso, LinearRegression
from sklearn.model_selection import RandomizedSearchCV, TimeSeriesSplit

import discrepancy as dc
from discrepancy import errors
from pysindy_helpers import pysindy_defaults, quiet

warnings.filterwarnings("ignore", module="pysindy")
TOL = dict(rtol=1e-8, atol=1e-8)
#: the user guide's page for PySINDy users (docs/guide/pysindy.md, linked from the README)
SECTION = (Path(__file__).parents[1] / "docs" / "guide" / "pysindy.md").read_text(
    encoding="utf-8")


def lorenz(t, z):
    return [10 * (z[1] - z[0]), z[0] * (28 - z[2]) - z[1], z[0] * z[1] - 8 / 3 * z[2]]


def documented(phrase: str) -> None:
    """The guide's PySINDy page states this difference (line breaks aside)."""
    assert " ".join(phrase.split()) in " ".join(SECTION.split()), \
        f"docs/guide/pysindy.md does not document {phrase!r}"


ours = pysindy_defaults


# PySINDy's test fixtures (its conftest, 2.x)
T1 = np.linspace(0, 1, 10)
X1 = 2 * T1.reshape(-1, 1)
T_BAD = np.linspace(0, 5, 10)
X_BAD = 2 * T_BAD
TL = np.linspace(0, 1, 12)
XL = solve_ivp(lorenz, (TL[0], TL[-1]), [8, 27, -7], t_eval=TL).y.T
TM = [np.linspace(0, 5, n) for n in (100, 200, 500)]
XM = [solve_ivp(lorenz, (t[0], t[-1]), x0, t_eval=t).y.T for t, x0 in zip(
    TM, [[8, 27, -7], [-10.9595724, 21.7346758, 24.5722540],
         [-3.95406365, -9.21825124, 12.07459147]], strict=True)]
XD = np.zeros(100)
XD[0] = 0.5
for _k in range(1, 100):
    XD[_k] = 3.6 * XD[_k - 1] * (1 - XD[_k - 1])
DATA = {"data_1d": (X1, T1), "data_lorenz": (XL, TL), "data_1d_bad_shape": (X_BAD, T_BAD)}


def same_coefficients(peer, mine):
    np.testing.assert_allclose(mine.coefficients(), peer.coefficients(), **TOL)


# ------------------------------------------------------------------ test_pysindy.py
@pytest.mark.parametrize("data", DATA)
def test_same_fit_predict_score_on_pysindys_fixtures(data):
    x, t = DATA[data]
    peer, mine = ps.SINDy().fit(x, t), ours().fit(x, t)
    same_coefficients(peer, mine)
    np.testing.assert_allclose(np.ravel(mine.predict(x)), np.ravel(peer.predict(x)), **TOL)
    # x = 2t: the derivative is constant, so R² divides rounding by rounding in both
    assert mine.score(x, t) <= 1 and peer.score(x, t) <= 1
    assert ours().fit(XM, TM).score(XM, TM) == pytest.approx(
        ps.SINDy().fit(XM, TM).score(XM, TM), rel=1e-9)


@pytest.mark.parametrize("data", ["data_1d", "data_1d_bad_shape"])
def test_same_simulate_on_pysindys_fixtures(data):
    x, t = DATA[data]
    peer, mine = ps.SINDy().fit(x, t), ours().fit(x, t)
    x0 = np.ravel(x[0]) if np.ndim(x) == 2 else x[:1]
    np.testing.assert_allclose(np.ravel(mine.simulate(x0, t, integrator="solve_ivp")),
                               np.ravel(peer.simulate(x0, t)), **TOL)


def test_documented_a_diverging_simulation_raises():
    """The model fitted to 12 samples of Lorenz blows up within the record: PySINDy's
    solver keeps stepping (it had not returned after 10 minutes), here SimulationError
    says where, at once, and keeps the rows reached."""
    mine = ours().fit(XL, TL)
    with pytest.raises(errors.SimulationError) as stop:
        mine.simulate(XL[0], TL, integrator="solve_ivp")
    assert 0 < len(stop.value.partial) < len(TL)
    documented("simulation that diverges raises `SimulationError`")


def test_same_feature_names_length_and_not_fitted_errors():
    for call in ("predict", "get_feature_names", "coefficients", "equations"):
        with pytest.raises(AttributeError):            # both are AttributeErrors
            getattr(ours(), call)(*([X1] if call == "predict" else []))
        with pytest.raises(AttributeError):
            getattr(ps.SINDy(), call)(*([X1] if call == "predict" else []))
    assert len(ours().fit(XL, TL).get_feature_names()) == 10 == \
        len(ps.SINDy().fit(XL, TL).get_feature_names())


def test_documented_not_fitted_error_is_ours_not_scikit_learns():
    from sklearn.exceptions import NotFittedError
    with pytest.raises(errors.NotFittedError):
        ours().predict(X1)
    assert not issubclass(errors.NotFittedError, NotFittedError)
    documented("not scikit-learn's `NotFittedError`")


def test_same_improper_shapes_are_reshaped():
    for kw in ({}, {"x_dot": X1.flatten()}):
        same_coefficients(ps.SINDy().fit(X1.flatten(), T1, **kw),
                          ours().fit(X1.flatten(), T1, **kw))
    same_coefficients(ps.SINDy().fit(X1, T1, x_dot=X1.flatten()),
                      ours().fit(X1, T1, x_dot=X1.flatten()))


def test_same_dropped_endpoints_fit():
    d = dict(drop_endpoints=True)
    same_coefficients(ps.SINDy(differentiation_method=ps.FiniteDifference(**d)).fit(XL, TL),
                      ours(differentiation_method=dc.FiniteDifference(**d)).fit(XL, TL))


@pytest.mark.parametrize("data", DATA)
def test_same_mixed_inputs_scalar_t_and_given_x_dot(data):
    x, t = DATA[data]
    same_coefficients(ps.SINDy().fit(x, t=2), ours().fit(x, t=2))
    same_coefficients(ps.SINDy().fit(x, t, x_dot=x), ours().fit(x, t, x_dot=x))


def test_documented_x_dot_without_t():
    """PySINDy 2.x needs t even with x_dot; here t may then be left out."""
    with pytest.raises(TypeError):
        ps.SINDy().fit(XL, x_dot=XL)
    same_coefficients(ps.SINDy().fit(XL, 1.0, x_dot=XL), ours().fit(XL, x_dot=XL))
    documented("unless `x_dot` is given")


@pytest.mark.parametrize("data", ["data_1d", "data_lorenz"])
def test_same_bad_t_is_refused(data):
    x, t = DATA[data]
    bad = [("1", ValueError), (-1, ValueError), (t[:-1], ValueError)]
    swapped = t.copy()
    swapped[2], swapped[4] = swapped[4], swapped[2]
    repeated = t.copy()
    repeated[3] = repeated[5]
    bad += [(swapped, ValueError), (repeated, ValueError)]
    for value, kind in bad:
        with pytest.raises(kind):
            ps.SINDy().fit(x, value)
        with pytest.raises(kind):
            ours().fit(x, value)
    with pytest.raises(errors.ParameterError, match="t is required"):
        ours().fit(x)                                    # PySINDy: a TypeError


def test_documented_t_as_a_list_of_times():
    """PySINDy refuses a Python list of times for one trajectory; here it is the times."""
    with pytest.raises(ValueError):
        ps.SINDy().fit(XL, list(TL))
    same_coefficients(ps.SINDy().fit(XL, TL), ours().fit(XL, list(TL)))
    documented("`t` may also be a Python list of times")


@pytest.mark.parametrize("make", [
    lambda: (ps.STLSQ(), dc.STLSQ(threshold=0.1)), lambda: (ps.SR3(), dc.SR3()),
    lambda: (Lasso(fit_intercept=False), Lasso(fit_intercept=False)),
    lambda: (ElasticNet(fit_intercept=False), ElasticNet(fit_intercept=False)),
    lambda: (ps.ConstrainedSR3(), dc.ConstrainedSR3())],
    ids=["stlsq", "sr3", "lasso", "elasticnet", "constrainedsr3"])
@pytest.mark.parametrize("data", ["data_1d", "data_lorenz"])
def test_same_predict_with_each_optimizer(data, make):
    x, t = DATA[data]
    peer_opt, our_opt = make()
    peer = quiet(ps.SINDy(optimizer=peer_opt).fit, x, t)
    mine = quiet(ours(optimizer=our_opt).fit, x, t)
    np.testing.assert_allclose(mine.coefficients(), np.reshape(peer.coefficients(), (-1, 10)
                               if data == "data_lorenz" else (1, -1)), rtol=1e-7, atol=1e-8)
    assert mine.predict(x).shape == x.shape and mine.coefficients().ndim == 2


def test_same_simulate_with_odeint_and_an_unknown_integrator_refused():
    x, t = XM[2], TM[2]
    peer, mine = ps.SINDy().fit(x, t), ours().fit(x, t)
    np.testing.assert_allclose(mine.simulate(x[0], t[:50], integrator="odeint"),
                               peer.simulate(x[0], t[:50], integrator="odeint"), rtol=1e-6)
    with pytest.raises(ValueError):
        peer.simulate(x[0], t, integrator="None")
    with pytest.raises(ValueError):
        mine.simulate(x[0], t, integrator="None")


def test_same_libraries_on_lorenz():
    """PySINDy's library test on its longest Lorenz run (on its 12 samples these libraries
    have more terms than samples: see the next case)."""
    x, t = XM[2], TM[2]
    cases = [(ps.PolynomialLibrary(degree=3), dc.PolynomialLibrary(3)),
             (ps.FourierLibrary(n_frequencies=3), dc.FourierLibrary(3)),
             (ps.PolynomialLibrary() + ps.FourierLibrary(), dc.PolynomialLibrary(2)
              + dc.FourierLibrary(1))]
    for peer_lib, our_lib in cases:
        peer = ps.SINDy(feature_library=peer_lib).fit(x, t)
        mine = ours(feature_library=our_lib).fit(x, t)
        same_coefficients(peer, mine)
        assert mine.score(x, t) == pytest.approx(peer.score(x, t), rel=1e-8)


def test_documented_more_terms_than_samples():
    """18 Fourier terms on 12 samples: many coefficient vectors fit exactly; PySINDy's refit
    returns the minimum-norm one, ours the minimum-norm one in equilibrated columns. Both
    reproduce the derivatives they were fitted to."""
    peer = ps.SINDy(feature_library=ps.FourierLibrary(n_frequencies=3)).fit(XL, TL)
    mine = ours(feature_library=dc.FourierLibrary(3)).fit(XL, TL)
    assert not np.allclose(mine.coefficients(), peer.coefficients(), rtol=1e-3)
    x_dot = ps.FiniteDifference()(XL, TL)
    for model in (peer, mine):
        assert np.abs(model.predict(XL) - x_dot).max() < 1e-6 * np.abs(x_dot).max()
    documented("more terms than samples")


def test_documented_custom_library_of_lambdas():
    """PySINDy's CustomLibrary(library_functions=[...]) of anonymous functions of any
    arity: here one-argument functions by name or sympy expressions; same columns."""
    peer = ps.CustomLibrary(library_functions=[lambda x: x, lambda x: x ** 2]).fit(XL)
    mine = dc.CustomLibrary(functions={"f": lambda x: x, "g": lambda x: x ** 2}).fit(
        ["x1", "x2", "x3"])
    np.testing.assert_allclose(mine.transform(XL), peer.transform(XL), **TOL)
    documented("`dc.CustomLibrary(functions={name: f})`")


def test_documented_smoothed_finite_difference_is_close_not_equal():
    t = np.linspace(0, 2, 200)
    x = np.c_[np.sin(3 * t), np.cos(t)]
    peer = ps.SmoothedFiniteDifference()._differentiate(x, t)
    mine = dc.SavitzkyGolay(11, 3)(x, t)
    exact = np.c_[3 * np.cos(3 * t), -np.sin(t)]
    inner = slice(10, -10)
    assert np.abs(mine - exact)[inner].max() < 1e-4 and np.abs(peer - exact)[inner].max() < 1e-2
    documented("(close, not equal)")


@pytest.mark.parametrize("data", DATA)
def test_documented_score_needs_t(data):
    x, t = DATA[data]
    peer, mine = ps.SINDy().fit(x, t), ours().fit(x, t)
    with pytest.raises(TypeError):
        peer.score(x)
    with pytest.raises(errors.ParameterError, match="score: t is required"):
        mine.score(x)
    assert mine.score(x, x_dot=x) == pytest.approx(peer.score(x, t, x_dot=x), rel=1e-9)
    documented("**t is required**")


def test_same_multiple_trajectories():
    peer, mine = ps.SINDy().fit(XM, TM), ours().fit(XM, TM)
    same_coefficients(peer, mine)
    assert mine.score(XM, TM) == pytest.approx(peer.score(XM, TM), rel=1e-9) and \
        mine.score(XM, TM) > 0.8
    for a, b in zip(mine.predict(XM), peer.predict(XM), strict=True):
        np.testing.assert_allclose(a, b, **TOL)
    same_coefficients(ps.SINDy().fit(XM, TM, x_dot=XM), ours().fit(XM, TM, x_dot=XM))



def test_one_time_array_is_shared_by_every_trajectory_as_in_pysindy():
    t = TM[1]
    xs = [solve_ivp(lorenz, (t[0], t[-1]), x0, t_eval=t).y.T for x0 in ([1, 2, 3], [-4, 2, 20])]
    peer, mine = ps.SINDy().fit(xs, t), ours().fit(xs, t)
    same_coefficients(peer, mine)
    np.testing.assert_array_equal(mine.coef_, ours().fit(xs, [t, t]).coef_)
    with pytest.raises(errors.ShapeError, match=r"^t\[1\] must be a step or a 1-D array of 100"):
        ours().fit([xs[0], xs[1][:100]], t)


def test_same_discrete_time_fit_predict_score_simulate():
    peer = ps.DiscreteSINDy().fit(XD, t=1)
    mine = ours(discrete_time=True, differentiation_method=None).fit(XD)
    same_coefficients(peer, mine)
    np.testing.assert_allclose(mine.predict(XD), peer.predict(XD), **TOL)
    # a chaotic map doubles rounding differences every step or so: 20 steps
    np.testing.assert_allclose(mine.simulate([XD[0]], 20), peer.simulate(XD[0], 20), **TOL)
    target = peer.simulate(XD[0], 20)[12, 0]     # PySINDy's test stops at a known state
    def stop(xi):
        return np.isclose(xi[0], target)
    np.testing.assert_allclose(mine.simulate([XD[0]], 100, stop_condition=stop),
                               peer.simulate(XD[0], 100, stop_condition=stop), **TOL)
    assert len(mine.simulate([XD[0]], 100, stop_condition=stop)) == 13
    assert mine.score(XD) == pytest.approx(peer.score(XD, t=1), rel=1e-9)
    assert mine.score(XD, x_dot=XD) < 1 and peer.score(XD, t=1, x_next=XD) < 1
    same_coefficients(ps.DiscreteSINDy().fit(XD[:-1], t=1, x_next=XD[1:]),
                      ours(discrete_time=True).fit(XD[:-1], x_dot=XD[1:]))


def test_documented_discrete_simulate_takes_an_integer():
    mine = ours(discrete_time=True).fit(XD)
    with pytest.raises(ValueError):
        ps.DiscreteSINDy().fit(XD, t=1).simulate(XD[0], t=[1, 2])
    assert len(mine.simulate([XD[0]], [1, 2])) == 2     # an array: its length of steps
    for bad in (-1, 0.5):
        with pytest.raises(ValueError):
            mine.simulate([XD[0]], bad)
    documented("its length is the number of steps")


def test_same_printed_equations_are_nonempty(capsys):
    for x, t in DATA.values():
        ours().fit(x, t).print(precision=2)
        assert capsys.readouterr().out.strip()
    ours(discrete_time=True).fit(XD).print()
    assert capsys.readouterr().out.startswith("(x1)[k+1] = ")


def test_documented_printed_names_start_at_x1(capsys):
    ps.SINDy().fit(XL, TL).print()
    peer = capsys.readouterr().out
    ours().fit(XL, TL).print()
    mine = capsys.readouterr().out
    assert peer.startswith("(x0)'") and mine.startswith("(x1)'")
    documented("**Names start at x1.**")


def test_same_differentiation_and_complexity():
    np.testing.assert_allclose(ours().differentiation_method(XL, TL),
                               ps.SINDy().differentiation_method(XL, TL), **TOL)
    peer, mine = ps.SINDy().fit(XL, TL), ours().fit(XL, TL)
    assert mine.complexity == peer.complexity and np.count_nonzero(mine.coefficients()) == \
        np.count_nonzero(peer.coefficients())


def test_same_simulate_refuses_a_scalar_t():
    with pytest.raises(ValueError):
        ps.SINDy().fit(XL, TL).simulate(XL[0], t=1)
    with pytest.raises(ValueError):
        ours().fit(XL, TL).simulate(XL[0], t=1)


def test_documented_fit_warnings_are_ours():
    """STLSQ's warnings: an empty model is a UserWarning in both; running out of iterations
    is our ConvergenceWarning (a UserWarning), not scikit-learn's class."""
    for model in (ps.SINDy(optimizer=ps.STLSQ(threshold=100)), ours(optimizer=dc.STLSQ(100.0))):
        with pytest.warns(UserWarning):
            model.fit(XL, TL)
    with pytest.warns(SklearnConvergenceWarning):
        ps.SINDy(optimizer=ps.STLSQ(max_iter=1)).fit(XL, TL)
    with pytest.warns(errors.ConvergenceWarning):
        ours(optimizer=dc.STLSQ(threshold=0.1, max_iter=1)).fit(XL, TL)
    documented("`discrepancy.errors.ConvergenceWarning`")


def test_documented_cross_validation_needs_metadata_routing():
    """PySINDy 1.x's RandomizedSearchCV case (t fixed by t_default) with routing here."""
    x = solve_ivp(lorenz, (0, 5), [8, 27, -7], t_eval=np.linspace(0, 5, 500)).y.T
    grid = {"optimizer__threshold": [0.01, 0.1], "feature_library__degree": [1, 2],
            "differentiation_method__order": [2, 4]}
    with sklearn.config_context(enable_metadata_routing=True), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        search = RandomizedSearchCV(ours(feature_library=dc.PolynomialLibrary(2)), grid,
                                    cv=TimeSeriesSplit(n_splits=3), n_iter=5, random_state=0)
        search.fit(x, t=5 / 499)
    assert np.all(np.isfinite(search.cv_results_["mean_test_score"]))
    documented("**Cross-validation carries t.**")


def test_same_linear_equality_constraints():
    pytest.importorskip("cvxpy")
    library = ps.PolynomialLibrary().fit(XL)
    p = library.n_output_features_
    lhs = np.zeros((2, 3 * p))
    lhs[0, 3], lhs[1, p] = 1, 3
    kw = dict(constraint_lhs=lhs, constraint_rhs=np.ones(2), equality_constraints=True)
    peer = ps.SINDy(feature_library=ps.PolynomialLibrary(), optimizer=ps.ConstrainedSR3(**kw))
    mine = ours(feature_library=dc.PolynomialLibrary(2), optimizer=dc.ConstrainedSR3(**kw))
    same_coefficients(peer.fit(XL, TL), mine.fit(XL, TL))


def test_same_sample_weights_per_trajectory():
    """PySINDy's sample-weight routing test: the weighted fit is the weighted mixture."""
    t = np.linspace(0, 2 * np.pi, 50)
    xa, xb = np.c_[np.cos(t), np.sin(t)], np.c_[np.cos(2 * t), np.sin(2 * t)]
    da, db = np.c_[-np.sin(t), np.cos(t)], np.c_[-2 * np.sin(2 * t), 2 * np.cos(2 * t)]
    w = [np.ones(50), np.ones(50), 10 * np.ones(50)]
    model = ours(optimizer=LinearRegression(fit_intercept=False))
    weighted = model.fit([xa, xa, xb], t=0.1, x_dot=[da, da, db], sample_weight=w)
    theta = np.vstack([ps.PolynomialLibrary().fit_transform(a) for a in (xa, xa, xb)])
    root = np.sqrt(np.concatenate(w))[:, None]
    expected = np.linalg.lstsq(theta * root, np.vstack([da, da, db]) * root, rcond=None)[0].T
    np.testing.assert_allclose(weighted.coefficients(), expected, rtol=1e-8, atol=1e-10)


# ------------------------------------------------------------------ docstring examples
def test_same_sindy_docstring_lorenz():
    t = np.arange(0, 2, 0.002)
    x = odeint(lambda z, tau: lorenz(tau, z), [-8, 8, 27], t)
    peer, mine = ps.SINDy().fit(x, t=t[1] - t[0]), ours().fit(x, t=t[1] - t[0])
    same_coefficients(peer, mine)
    assert mine.score(x, t=t[1] - t[0]) == pytest.approx(peer.score(x, t=t[1] - t[0]), rel=1e-10)


def test_same_sindy_docstring_with_control():
    def rhs(t, z):
        return [10 * (z[1] - z[0]) + np.sin(2 * t) ** 2, z[0] * (28 - z[2]) - z[1],
                z[0] * z[1] - 8 / 3 * z[2]]
    t = np.arange(0, 2, 0.002)
    x = solve_ivp(rhs, (0, 2), [-8, 8, 27], t_eval=t, rtol=1e-10, atol=1e-10).y.T
    u = np.sin(2 * t)
    peer, mine = ps.SINDy().fit(x, t[1] - t[0], u=u), ours().fit(x, t[1] - t[0], u=u)
    same_coefficients(peer, mine)
    assert mine.score(x, t[1] - t[0], u=u) == pytest.approx(
        peer.score(x, t[1] - t[0], u=u), rel=1e-10)


def test_same_discrete_sindy_docstring_noisy_logistic_map():
    rng = np.random.default_rng(0)
    x = np.zeros(20)
    x[0] = 0.5
    for i in range(1, 20):
        x[i] = 3.6 * x[i - 1] * (1 - x[i - 1]) + 0.001 * rng.normal()
    peer = ps.DiscreteSINDy().fit(x[:16], t=1)
    mine = ours(discrete_time=True).fit(x[:16])
    same_coefficients(peer, mine)
    np.testing.assert_allclose(mine.predict(x[16:]), peer.predict(x[16:]), **TOL)
    np.testing.assert_allclose(mine.simulate([0.5], 20), peer.simulate(np.array([0.5]), 20),
                               **TOL)


def test_documented_parameterized_library_as_inputs():
    """DiscreteSINDy's ParameterizedLibrary example (logistic maps at four r): the parameter
    is an input, the library a product; the same law x[k+1] = r x - r x^2."""
    xs = []
    for r in (3.6, 3.7, 3.8, 3.9):
        x = np.zeros(500)
        x[0] = 0.5
        for i in range(1, 500):
            x[i] = r * x[i - 1] * (1 - x[i - 1])
        xs.append(x[:, None])
    us = [np.full((500, 1), r) for r in (3.6, 3.7, 3.8, 3.9)]
    lib = dc.PolynomialLibrary(3, variables=["x"]) * dc.PolynomialLibrary(1, variables=["r"])
    model = ours(discrete_time=True, feature_library=lib, state_names=["x"],
                 input_names=["r"]).fit(xs, u=us)
    names = model.get_feature_names()
    found = {names[j]: c for j, c in enumerate(model.coefficients()[0]) if abs(c) > 1e-9}
    assert set(found) == {"x r", "x^2 r"}
    np.testing.assert_allclose([found["x r"], found["x^2 r"]], [1, -1], rtol=1e-9)
    documented("parameters as inputs")


def test_same_stlsq_and_sr3_docstrings():
    t = np.arange(0, 2, 0.002)
    x = odeint(lambda z, tau: lorenz(tau, z), [-8, 8, 27], t)
    for peer_opt, our_opt in ((ps.STLSQ(threshold=0.1, alpha=0.5), dc.STLSQ(0.1, 0.5)),
                              (ps.SR3(reg_weight_lam=0.1, relax_coeff_nu=1),
                               dc.SR3(0.1, relax_coeff_nu=1))):
        same_coefficients(quiet(ps.SINDy(optimizer=peer_opt).fit, x, t=t[1] - t[0]),
                          quiet(ours(optimizer=our_opt).fit, x, t=t[1] - t[0]))


def test_same_finite_difference_and_spectral_docstrings():
    t = np.linspace(0, 1, 5)
    x = np.vstack((np.sin(t), np.cos(t))).T
    np.testing.assert_allclose(dc.FiniteDifference()(x, t),
                               ps.FiniteDifference()._differentiate(x, t), **TOL)
    t = np.arange(0, 1, 0.1)
    x = np.vstack((np.sin(t), np.cos(t))).T
    np.testing.assert_allclose(dc.Spectral()(x, t), ps.SpectralDerivative()._differentiate(x, t),
                               **TOL)


def test_same_library_docstrings_values():
    """Fourier, concatenated, tensored and generalized libraries: the same columns."""
    x = np.array([[0.0, -1], [1.0, 0.0], [2.0, -1.0]])
    names = ["x1", "x2"]
    peer = ps.FourierLibrary(n_frequencies=2).fit(x[:, :1])
    np.testing.assert_allclose(dc.FourierLibrary(2).fit(["x1"]).transform(x[:, :1]),
                               peer.transform(x[:, :1]), **TOL)
    poly, fourier = ps.PolynomialLibrary(degree=2, include_bias=False), ps.FourierLibrary()
    ours_poly = dc.PolynomialLibrary(2, include_bias=False)
    for peer_lib, our_lib in ((poly + fourier, ours_poly + dc.FourierLibrary(1)),
                              (poly * fourier, ours_poly * dc.FourierLibrary(1)),
                              (ps.GeneralizedLibrary([poly, fourier], tensor_array=[[1, 1]]),
                               ours_poly + dc.FourierLibrary(1)
                               + ours_poly * dc.FourierLibrary(1))):
        np.testing.assert_allclose(our_lib.fit(names).transform(x),
                                   peer_lib.fit(x).transform(x), **TOL)


def test_documented_duplicate_columns_are_kept_once():
    """A product with a constant column repeats the other library's columns (``1 sin(x0)``
    next to ``sin(x0)``): PySINDy keeps both, here each expression is one column."""
    x = np.array([[0.0, -1], [1.0, 0.0], [2.0, -1.0]])
    peer = ps.GeneralizedLibrary([ps.PolynomialLibrary(degree=2), ps.FourierLibrary()],
                                 tensor_array=[[1, 1]]).fit(x)
    mine = (dc.PolynomialLibrary(2) + dc.FourierLibrary(1)
            + dc.PolynomialLibrary(2) * dc.FourierLibrary(1)).fit(["x1", "x2"])
    assert peer.transform(x).shape[1] == mine.transform(x).shape[1] + 4
    documented("duplicate columns")


def test_same_libraries_fitted_to_data_and_model_attributes():
    x = np.array([[0.0, -1], [1.0, 0.0], [2.0, -1.0]])
    for peer_lib, our_lib in ((ps.PolynomialLibrary(degree=3), dc.PolynomialLibrary(3)),
                              (ps.FourierLibrary(n_frequencies=2), dc.FourierLibrary(2))):
        np.testing.assert_allclose(our_lib.fit(x).transform(x), peer_lib.fit(x).transform(x),
                                   **TOL)
        np.testing.assert_allclose(our_lib.fit_transform(x), peer_lib.fit_transform(x), **TOL)
    t = np.arange(0, 2, 0.002)
    x = odeint(lambda z, tau: lorenz(tau, z), [-8, 8, 27], t)
    peer, mine = ps.SINDy().fit(x, t, u=np.sin(t)), ours().fit(x, t, u=np.sin(t))
    for name in ("n_features_in_", "n_control_features_", "n_output_features_"):
        assert getattr(mine, name) == getattr(peer, name)
    assert len(mine.feature_names) == len(peer.feature_names) == 4


def test_documented_library_feature_names():
    peer = ps.FourierLibrary(n_frequencies=2).fit(np.zeros((3, 1))).get_feature_names()
    mine = dc.FourierLibrary(2).fit(["x1"]).get_feature_names()
    assert peer[0] == "sin(1 x0)" and mine[0] == "sin(x1)"
    documented("**Printed equations**")


# ------------------------------------------------------------------ options of issue 23
def test_same_ensemble_docstring_style_fit():
    t = np.arange(0, 4, 0.002)
    x = solve_ivp(lorenz, (0, 4), [-8, 8, 27], t_eval=t, rtol=1e-10, atol=1e-10).y.T
    x = x + 0.05 * np.random.default_rng(1).normal(size=x.shape)
    np.random.seed(100)  # noqa: NPY002  (PySINDy draws from the global generator)
    peer = ps.SINDy(optimizer=ps.EnsembleOptimizer(ps.STLSQ(), bagging=True, n_subset=1000,
                                                   n_models=10)).fit(x, t)
    np.random.seed(100)  # noqa: NPY002  (PySINDy draws from the global generator)
    mine = ours(optimizer=dc.EnsembleOptimizer(dc.STLSQ(threshold=0.1), bagging=True,
                                               n_subset=1000, n_models=10)).fit(x, t)
    same_coefficients(peer, mine)


def test_same_trimming_on_pysindys_corrupted_oscillator():
    t = np.linspace(0, 1, 100)
    x, y = 3 * np.exp(-2 * t), 0.5 * np.exp(t)
    corrupt = np.random.default_rng(1).choice(np.arange(1, 99), 5)
    x[corrupt] = 0
    X = np.stack((x, y), axis=-1)
    X_dot = ps.FiniteDifference(order=2)(X, t)
    kw = dict(reg_weight_lam=0.1, trimming_fraction=0.1, max_iter=200)
    peer = quiet(ps.SR3(**kw).fit, X, X_dot)
    mine = quiet(dc.SR3(**kw).fit, X, X_dot)
    np.testing.assert_allclose(mine.coef_, peer.coef_, **TOL)
    np.testing.assert_allclose(mine.trimming_array, peer.trimming_array, rtol=1e-8, atol=1e-10)


def test_documented_default_model_on_a_ten_sample_record():
    with pytest.warns(errors.ShortRecordWarning):
        mine = dc.DiscrepancyModel().fit(X1, T1)
    same_coefficients(ps.SINDy().fit(X1, T1), mine)
    documented("**Short records fall back**")


def test_the_readme_maps_every_public_pysindy_name():
    """Every name in ``pysindy.__all__`` and its submodules' public names has a row (or a
    mention) on the guide's "Coming from PySINDy" page."""
    import importlib
    import inspect

    names = set()
    for module in ("pysindy", "pysindy.differentiation", "pysindy.feature_library",
                   "pysindy.feature_library.base", "pysindy.optimizers", "pysindy.utils",
                   "pysindy.deeptime"):
        mod = importlib.import_module(module)
        public = getattr(mod, "__all__", None) or [n for n in dir(mod) if not n.startswith("_")]
        for name in public:
            obj = getattr(mod, name, None)
            home = obj.__name__ if inspect.ismodule(obj) else getattr(obj, "__module__", "")
            if obj is None or (home or "").startswith("pysindy"):
                names.add(name)
    names |= {n for n in dir(ps) if not n.startswith("_") and
              getattr(getattr(ps, n), "__module__", "").startswith("pysindy")}
    missing = sorted(n for n in names if f"`{n}" not in SECTION and f".{n}" not in SECTION
                     and f" {n}`" not in SECTION)
    assert not missing, f"docs/guide/pysindy.md does not mention {missing}"
    assert len(names) >= 60


# ------------------------------------------------------------------ test_optimizers.py
def _quadratic(rng):
    x = rng.standard_normal((100, 3))
    return x, ps.PolynomialLibrary(degree=2, include_bias=False).fit_transform(x)


@pytest.mark.parametrize("params", [
    dict(regularizer="l1", reg_weight_lam=1e-5), dict(regularizer="l2", reg_weight_lam=1e-5),
    dict(regularizer="weighted_l1", reg_weight_lam=1e-5 * np.ones((3, 9))),
    dict(regularizer="weighted_l2", reg_weight_lam=np.zeros((3, 9)))],
    ids=["l1", "l2", "weighted_l1", "weighted_l2"])
def test_same_constrained_sr3_with_identity_constraints(rng, params):
    """PySINDy's quadratic-library case: the first p coefficients constrained to zero (the
    kind of constraint unsaid: equalities, with a warning, in both)."""
    x, theta = _quadratic(rng)
    y = theta @ rng.normal(size=(9, 3))
    kw = dict(constraint_lhs=np.eye(6, 27), constraint_rhs=np.zeros(6), **params)
    with pytest.warns(UserWarning, match="equalit"):
        mine = dc.ConstrainedSR3(**kw).fit(theta, y)
    assert np.allclose(mine.coef_.ravel()[:6], 0.0)
    pytest.importorskip("cvxpy")
    peer = quiet(ps.ConstrainedSR3(**kw).fit, theta, y)
    np.testing.assert_allclose(mine.coef_, peer.coef_, **TOL)


@pytest.mark.parametrize("make", [lambda: (ps.STLSQ(), dc.STLSQ(threshold=0.1)),
                                  lambda: (ps.SR3(), dc.SR3()),
                                  lambda: (ps.ConstrainedSR3(), dc.ConstrainedSR3())],
                         ids=["stlsq", "sr3", "constrainedsr3"])
def test_same_sample_weights_of_zero_drop_samples(make):
    """PySINDy's sample-weight case: every other weight 0 is the other samples alone."""
    peer, mine = make()
    w = np.ones(len(X1))
    w[::2] = 0
    np.testing.assert_allclose(mine.fit(X1, X1, sample_weight=w).coef_,
                               quiet(peer.fit, X1, X1, sample_weight=w).coef_, **TOL)
    np.testing.assert_allclose(make()[1].fit(X1[1::2], X1[1::2]).coef_, mine.coef_,
                               rtol=1e-10, atol=1e-12)


def test_same_optimizer_predict_and_complexity():
    x = np.c_[2 * np.linspace(1, 100, 100), -10 * np.linspace(1, 100, 100)]
    x_dot = np.ones((100, 2)) * [2, -10]
    for opt in (dc.STLSQ(threshold=0.1), dc.SR3()):
        with pytest.raises(AttributeError):            # not fitted, as PySINDy's
            _ = opt.complexity
        opt.fit(x, x)
        assert opt.complexity > 0 and opt.predict(x).shape == x.shape
    peer = ps.STLSQ().fit(x, x_dot)
    np.testing.assert_allclose(dc.STLSQ(threshold=0.1).fit(x, x_dot).predict(x),
                               peer.predict(x), **TOL)


def test_documented_parameters_are_checked_when_used():
    """PySINDy refuses STLSQ(threshold=-1) in its constructor; here (scikit-learn's
    contract) the constructor stores it and fit refuses it, naming it."""
    with pytest.raises(ValueError):
        ps.STLSQ(threshold=-1)
    bad = dc.STLSQ(threshold=-1)
    with pytest.raises(errors.ParameterError, match="threshold"):
        bad.fit(X1, X1)
    documented("checked when they are used")
