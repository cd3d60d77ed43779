"""Every DiscrepancyModel method on a discrete-time model (a map): right against iterating
the map by hand, or refused by name."""
from __future__ import annotations

import numpy as np
import pytest

import discrepancy as dc
from discrepancy.errors import ParameterError
from discrepancy.symbolic import symbol

A, B = 0.5, 1.0


def hand(x0, u, k):
    """``k`` states of ``x[j+1] = A x[j] + B u[j]`` from ``x0``, iterated by hand."""
    out = [float(x0)]
    for j in range(k - 1):
        out.append(A * out[-1] + B * float(u[j]))
    return np.array(out)


RNG = np.random.default_rng(1)
U = RNG.uniform(-1, 1, (200, 1))
X = hand(0.3, U[:, 0], 200)[:, None]


@pytest.fixture(scope="module")
def fitted():
    """A map fitted on exact samples: x1[k+1] = 0.5 x1 + 1.0 u."""
    return dc.DiscrepancyModel(feature_library="poly(1)", optimizer=dc.STLSQ(threshold=0.05),
                               discrete_time=True, selection="optimizer").fit(X, u=U)


def test_the_fit_recovers_the_map(fitted):
    names = fitted.get_feature_names()
    np.testing.assert_allclose(fitted.coef_[0, names.index("x1")], A, atol=1e-10)
    np.testing.assert_allclose(fitted.coef_[0, names.index("u")], B, atol=1e-10)


@pytest.mark.parametrize("steps", [1, 3, 10])
def test_predict_ahead_iterates_the_map(fitted, steps):
    ahead = fitted.predict_ahead(X[:50], u=U[:50], steps=steps)
    expected = [hand(X[i, 0], U[i:, 0], steps + 1)[-1] for i in range(50 - steps)]
    np.testing.assert_allclose(ahead[:, 0], expected, atol=1e-9)


def test_predict_ahead_of_a_decay_is_the_decay_not_an_ode():
    model = dc.DiscrepancyModel.from_prior([0.9 * symbol("x")], state_names=["x"],
                                           discrete_time=True)
    x = np.array([[1.0], [0.9], [0.81]])
    np.testing.assert_allclose(model.predict_ahead(x, t=1.0)[:, 0], [0.9, 0.81], rtol=1e-15)
    np.testing.assert_allclose(model.predict_ahead(x, steps=2)[:, 0], [0.81], rtol=1e-15)


@pytest.mark.parametrize("method", ["fit_outputs", "refine", "estimate_initial_state"])
def test_output_error_methods_refuse_maps_by_name(fitted, method):
    model = fitted if method != "fit_outputs" else dc.DiscrepancyModel(discrete_time=True)
    with pytest.raises(ParameterError, match=rf"{method} .*discrete_time=True"):
        getattr(model, method)(X[:, 0], u=U, outputs=["x1"])


def test_simulate_and_its_interval_follow_the_map(fitted):
    np.testing.assert_allclose(fitted.simulate(X[0], 20, u=U[:20])[:, 0], X[:20, 0],
                               atol=1e-9)
    uncertainty = fitted.bootstrap(X, u=U, n_resamples=20)
    low, high = fitted.simulate_interval(X[0], 20, u=U[:20], uncertainty=uncertainty)
    np.testing.assert_allclose(low[:, 0], X[:20, 0], atol=1e-8)
    np.testing.assert_allclose(high[:, 0], X[:20, 0], atol=1e-8)


def test_bootstrap_of_a_noisy_map_covers_the_true_coefficients():
    x = X + 0.01 * np.random.default_rng(2).standard_normal(X.shape)
    model = dc.DiscrepancyModel(feature_library="poly(1)", optimizer=dc.STLSQ(threshold=0.05),
                                discrete_time=True, selection="optimizer").fit(x, u=U)
    low, high = model.bootstrap(x, u=U, n_resamples=100).interval(0.99)
    names = model.get_feature_names()
    for term, true in (("x1", A), ("u", B)):
        j = names.index(term)
        assert low[0, j] <= true <= high[0, j], (term, low[0, j], high[0, j])


def test_predict_interval_holds_the_next_state(fitted):
    uncertainty = fitted.bootstrap(X, u=U, n_resamples=20)
    low, high = fitted.predict_interval(X[:10], U[:10], uncertainty=uncertainty)
    np.testing.assert_allclose(low[:, 0], X[1:11, 0], atol=1e-8)
    np.testing.assert_allclose(high[:, 0], X[1:11, 0], atol=1e-8)


def test_trajectory_score_of_the_exact_map_is_zero(fitted):
    assert fitted.score(X, u=U, metric="trajectory") < 1e-8


def test_export_is_the_map(fitted):
    pytest.importorskip("casadi")
    f = fitted.to_casadi()
    assert f.name_out(0) == "x_next"
    np.testing.assert_allclose(float(f(0.4, -0.2)), A * 0.4 + B * -0.2, atol=1e-10)
    expr = fitted.to_sympy()[0]
    assert abs(float(expr.subs({symbol("x1"): 0.4, symbol("u"): -0.2})) - (A * 0.4 - B * 0.2)) \
        < 1e-10


def test_latex_of_a_map_has_next_states_not_rates(fitted):
    latex = fitted.to_latex(precision=3)
    assert "x_{1}[k+1] &=" in latex and r"\dot" not in latex


def test_control_refuses_a_map_by_name(fitted):
    pytest.importorskip("casadi")
    from discrepancy.control import MPC
    with pytest.raises(ParameterError, match="model is discrete-time"):
        MPC(fitted, dt=0.1)
