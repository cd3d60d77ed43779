"""DiscrepancyModel: known true coefficients, plain SINDy on Lorenz, joins, inputs, simulation."""
from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from sklearn.base import clone

import discrepancy as dc
from discrepancy.errors import NotFittedError, ParameterError, ShapeError
from discrepancy.models.core.uncertainty import CoefficientUncertainty
from discrepancy.symbolic import symbol

x1, x2, u = symbol("x1"), symbol("x2"), symbol("u")

# the paper's eq. (24): 1, x1, x2, x1 x2, x1^2 x2, x1 x2^2, x1^2 x2^2
PAPER_LIBRARY = [sp.Integer(1), x1, x2, x1 * x2, x1**2 * x2, x1 * x2**2, x1**2 * x2**2]


def prior_parameter(x, u=None):
    """Van der Pol with the wrong alpha 0.1 (truth 0.5)."""
    return np.column_stack([x[:, 1], 0.1 * (1 - x[:, 0] ** 2) * x[:, 1] - x[:, 0]])


def prior_structure(x, u=None):
    """Van der Pol missing -x1 in the second equation."""
    return np.column_stack([x[:, 1], 0.5 * (1 - x[:, 0] ** 2) * x[:, 1]])


SYMPY_PRIOR = [x2, sp.Rational(1, 10) * (1 - x1**2) * x2 - x1]
TRUE_VDP = [x2, sp.Rational(1, 2) * (1 - x1**2) * x2 - x1]


def coefficient_table(model):
    """{(state index, feature name): coefficient} of the non-zero terms."""
    names = model.get_feature_names()
    coef = model.coefficients()
    return {(i, names[j]): coef[i, j] for i, j in zip(*np.nonzero(coef), strict=True)}


def assert_terms(model, expected, rtol=0.01):
    """The active terms are exactly ``expected`` ({(state, name): value}), each within rtol."""
    found = coefficient_table(model)
    assert set(found) == set(expected), found
    for key, value in expected.items():
        assert abs(found[key] - value) <= rtol * abs(value), (key, found[key], value)


def noisy(data, seed, sigma=0.01):
    return data.x + sigma * np.random.default_rng(seed).normal(size=data.x.shape)


def libraries():
    return {"paper_eq24": dc.CustomLibrary(expressions=PAPER_LIBRARY),
            "poly4": dc.PolynomialLibrary(degree=4)}


@pytest.mark.parametrize("seed", [0, 1])
@pytest.mark.parametrize("library", ["paper_eq24", "poly4"])
def test_van_der_pol_parameter_case(vdp_data, seed, library):
    model = dc.DiscrepancyModel(prior=prior_parameter, feature_library=libraries()[library],
                                optimizer=dc.STLSQ(threshold=0.05),
                                differentiation_method=dc.SavitzkyGolay(window_length=21,
                                                                        polyorder=3))
    model.fit(noisy(vdp_data, seed), t=vdp_data.dt)
    assert_terms(model, {(1, "x2"): 0.4, (1, "x1^2 x2"): -0.4})


@pytest.mark.parametrize("seed", [0, 1])
@pytest.mark.parametrize("library", ["paper_eq24", "poly4"])
def test_van_der_pol_structure_case(vdp_data, seed, library):
    model = dc.DiscrepancyModel(prior=prior_structure, feature_library=libraries()[library],
                                optimizer=dc.STLSQ(threshold=0.05),
                                differentiation_method="savitzky_golay")
    model.fit(noisy(vdp_data, seed), t=vdp_data.t)
    assert_terms(model, {(1, "x1"): -1.0})


LORENZ_TERMS = {(0, "x1"): -10.0, (0, "x2"): 10.0, (1, "x1"): 28.0, (1, "x2"): -1.0,
                (1, "x1 x3"): -1.0, (2, "x3"): -8.0 / 3.0, (2, "x1 x2"): 1.0}


@pytest.mark.parametrize("method", [dc.FiniteDifference(),
                                    dc.SavitzkyGolay(window_length=7, polyorder=3)],
                         ids=["finite_difference", "savitzky_golay"])
def test_plain_sindy_recovers_lorenz(lorenz_data, method):
    model = dc.DiscrepancyModel(prior=None, feature_library=dc.PolynomialLibrary(degree=2),
                                optimizer=dc.STLSQ(threshold=0.5), differentiation_method=method)
    model.fit(lorenz_data.x, t=lorenz_data.dt)
    assert_terms(model, LORENZ_TERMS, rtol=0.01)
    # no prior: the printed equations have no "prior" part
    assert not any("prior" in eq for eq in model.equations())


def test_plain_sindy_with_given_derivatives_is_exact(lorenz_data):
    model = dc.DiscrepancyModel(feature_library=dc.PolynomialLibrary(degree=2),
                                optimizer=dc.STLSQ(threshold=0.5))
    model.fit(lorenz_data.x, t=lorenz_data.dt, x_dot=lorenz_data.x_dot)
    assert_terms(model, LORENZ_TERMS, rtol=1e-9)


@pytest.mark.parametrize("several", [False, True], ids=["one", "list"])
def test_plain_sindy_pipeline_equals_pysindy(lorenz_data, helpers, several):
    """Same data, finite differences, library and STLSQ: same coefficients as pysindy.SINDy."""
    import warnings

    import pysindy as ps

    x = lorenz_data.x + 0.05 * np.random.default_rng(0).normal(size=lorenz_data.x.shape)
    if several:
        x = [x, helpers.integrate(helpers.lorenz_rhs, [1.0, 1.0, 1.0], lorenz_data.t[:1500])]
    ours = dc.DiscrepancyModel(feature_library=dc.PolynomialLibrary(degree=2),
                               optimizer=dc.STLSQ(threshold=0.5),
                               differentiation_method=dc.FiniteDifference()).fit(x, t=0.002)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        peer = ps.SINDy(feature_library=ps.PolynomialLibrary(degree=2),
                        optimizer=ps.STLSQ(threshold=0.5),
                        differentiation_method=ps.FiniteDifference()).fit(x, t=0.002)
    np.testing.assert_allclose(ours.coefficients(), peer.coefficients(), rtol=0, atol=1e-8)
    assert np.count_nonzero(ours.coefficients()) == 7


def _vdp_pieces(helpers):
    """Two Van der Pol trajectories that do not meet: joining them creates a jump."""
    t = np.arange(801) * 0.01
    f = helpers.vdp_rhs(0.5)
    return t, [helpers.integrate(f, [0.5, 0.0], t), helpers.integrate(f, [-2.5, 2.0], t)]


def test_trajectories_in_a_list_are_not_differentiated_across_joins(helpers):
    t, pieces = _vdp_pieces(helpers)
    kw = dict(prior=prior_parameter, feature_library=dc.CustomLibrary(expressions=PAPER_LIBRARY),
              optimizer=dc.STLSQ(threshold=0.05), differentiation_method=dc.FiniteDifference())
    model = dc.DiscrepancyModel(**kw).fit(pieces, t=0.01)
    assert_terms(model, {(1, "x2"): 0.4, (1, "x1^2 x2"): -0.4}, rtol=1e-3)
    # reference: differentiate each piece by itself (numpy) and hand the derivatives over
    by_hand = dc.DiscrepancyModel(**kw).fit(
        np.vstack(pieces), t=np.arange(2 * len(t)) * 0.01,
        x_dot=np.vstack([np.gradient(p, t, axis=0, edge_order=2) for p in pieces]))
    np.testing.assert_allclose(model.coefficients(), by_hand.coefficients(), rtol=1e-9,
                               atol=1e-12)
    # the construction is sensitive: differentiating across the join corrupts the fit
    joined = dc.DiscrepancyModel(**kw).fit(np.vstack(pieces), t=0.01)
    assert np.max(np.abs(joined.coefficients() - model.coefficients())) > 0.01


@pytest.mark.parametrize("lengths", [
    (600, 600),
    (600, 400)])
def test_trajectories_with_their_own_times(helpers, lengths):
    f = helpers.vdp_rhs(0.5)
    ts = [np.arange(lengths[0]) * 0.01, np.arange(lengths[1]) * 0.02 + 3.0]
    xs = [helpers.integrate(f, [0.5, 0.0], ts[0]), helpers.integrate(f, [1.0, -1.0], ts[1])]
    model = dc.DiscrepancyModel(prior=prior_structure,
                                feature_library=dc.PolynomialLibrary(degree=3),
                                optimizer=dc.STLSQ(threshold=0.05),
                                differentiation_method=dc.SavitzkyGolay(window_length=9))
    model.fit(xs, t=ts)
    assert_terms(model, {(1, "x1"): -1.0}, rtol=1e-3)


def test_chunked_accumulation_gives_the_same_model(vdp_data):
    kw = dict(prior=prior_parameter, feature_library=dc.PolynomialLibrary(degree=4),
              optimizer=dc.STLSQ(threshold=0.05), differentiation_method="savitzky_golay")
    x = noisy(vdp_data, 3)
    whole = dc.DiscrepancyModel(**kw).fit(x, t=vdp_data.dt)
    chunks = (dc.Chunk(x[i:i + 97]) for i in range(0, len(x), 97))   # odd size: halos matter
    chunked = dc.DiscrepancyModel(**kw).fit(chunks, t=vdp_data.dt)
    np.testing.assert_allclose(chunked.coefficients(), whole.coefficients(), rtol=1e-9,
                               atol=1e-12)


# ----------------------------------------------------------------------- inputs

GAIN = 0.8


def forced_rhs(x, u):
    """x1' = x2, x2' = -x1 - 0.2 x2 + 0.8 sin(x1) u (true); the prior lacks the input term."""
    x = np.atleast_2d(x)
    u = np.atleast_2d(u)
    return np.column_stack([x[:, 1], -x[:, 0] - 0.2 * x[:, 1] + GAIN * np.sin(x[:, 0]) * u[:, 0]])


def forced_prior(x, u):
    return np.column_stack([x[:, 1], -x[:, 0] - 0.2 * x[:, 1]])


def u_of_t(t):
    return np.array([np.sin(1.3 * t) + 0.5 * np.cos(3.1 * t)])


@pytest.fixture(scope="module")
def forced_data(helpers):
    t = np.arange(3001) * 0.01
    x = helpers.integrate(lambda x, uu: forced_rhs(x, uu)[0], [1.0, 0.0], t, u=u_of_t)
    return t, x, np.array([u_of_t(tau) for tau in t])


def control_library():
    return (dc.PolynomialLibrary(degree=2, variables=["x1", "x2"])
            + dc.FourierLibrary(variables=["x1"]) * dc.PolynomialLibrary(
                degree=1, include_bias=False, variables=["u"]))


@pytest.mark.parametrize("library", [
    control_library,
    lambda: dc.CustomLibrary(expressions=[x1, x2, x1 * u, sp.sin(x1) * u, sp.cos(x1) * u, u])],
    ids=["tensor", "custom"])
def test_control_discrepancy_is_recovered(forced_data, library):
    t, x, uu = forced_data
    # x1 u and sin(x1) u are nearly collinear for small x1; a strong ridge would share the
    # coefficient between them and keep both, so this test uses a weak one
    model = dc.DiscrepancyModel(prior=forced_prior, feature_library=library(),
                                optimizer=dc.STLSQ(threshold=0.05, alpha=1e-6),
                                differentiation_method=dc.SavitzkyGolay(window_length=11))
    model.fit(x, t=t, u=uu)
    assert model.input_names_ == ["u"]
    assert_terms(model, {(1, "sin(x1) u"): GAIN})


def test_control_discrepancy_with_several_inputs_in_a_list(forced_data, helpers):
    t, x, uu = forced_data
    # a second recording with another input signal; a constant second input column u2
    # that the true system ignores
    law = lambda tau: np.array([np.cos(0.7 * tau)])  # noqa: E731
    x_b = helpers.integrate(lambda s, v: forced_rhs(s, v)[0], [-0.5, 0.3], t, u=law)
    u_b = np.array([law(tau) for tau in t])
    us = [np.hstack([uu, np.ones_like(uu)]), np.hstack([u_b, -np.ones_like(u_b)])]
    lib = (dc.PolynomialLibrary(degree=1, variables=["x1", "x2"])
           + dc.FourierLibrary(variables=["x1"]) * dc.PolynomialLibrary(
               degree=1, include_bias=False, variables=["u1", "u2"]))
    model = dc.DiscrepancyModel(prior=lambda s, v: forced_prior(s, v[:, :1]),
                                feature_library=lib, optimizer=dc.STLSQ(threshold=0.05),
                                differentiation_method=dc.SavitzkyGolay(window_length=11))
    model.fit([x, x_b], t=0.01, u=us)
    assert model.input_names_ == ["u1", "u2"]
    assert_terms(model, {(1, "sin(x1) u1"): GAIN})


# ---------------------------------------------------------- evaluation and export

@pytest.fixture(scope="module")
def exact_model(vdp_data):
    """Parameter case fitted on exact derivatives: coefficients equal 0.4 to round-off."""
    model = dc.DiscrepancyModel(prior=prior_parameter,
                                feature_library=dc.PolynomialLibrary(degree=3),
                                optimizer=dc.STLSQ(threshold=0.05))
    return model.fit(vdp_data.x, t=vdp_data.dt, x_dot=vdp_data.x_dot)


def test_predict_is_prior_plus_discrepancy(exact_model, rng):
    x = rng.uniform(-2, 2, size=(200, 2))
    g = exact_model.discrepancy(x)
    np.testing.assert_allclose(g[:, 0], 0.0, atol=1e-12)
    np.testing.assert_allclose(g[:, 1], 0.4 * x[:, 1] - 0.4 * x[:, 0] ** 2 * x[:, 1], atol=1e-9)
    np.testing.assert_allclose(exact_model.predict(x), prior_parameter(x) + g, rtol=1e-14,
                               atol=1e-14)
    # and the hybrid model is the true system
    np.testing.assert_allclose(exact_model.predict(x), forced_free_vdp(x), atol=1e-9)


def forced_free_vdp(x):
    return np.column_stack([x[:, 1], 0.5 * (1 - x[:, 0] ** 2) * x[:, 1] - x[:, 0]])


def test_equations_and_print(exact_model, capsys):
    assert exact_model.equations() == ["prior", "prior + 0.400 x2 - 0.400 x1^2 x2"]
    exact_model.print()
    out = capsys.readouterr().out.splitlines()
    assert out == ["(x1)' = prior", "(x2)' = prior + 0.400 x2 - 0.400 x1^2 x2"]
    assert exact_model.get_feature_names()[:4] == ["1", "x1", "x2", "x1^2"]


def test_a_small_coefficient_is_printed_not_hidden(exact_model):
    """A coefficient that rounds to 0 at the precision is shown with as many significant
    digits (PySINDy leaves the term out: a 2e-4 u^2 with u of 300 adds 18 to the rate)."""
    coef = exact_model.coef_.copy()
    coef[0, 1] = -1.954e-4
    small = exact_model.with_coefficients(coef)
    assert small.equations()[0] == "prior - 1.95e-04 x1"
    assert small.equations(precision=5)[0] == "prior - 0.00020 x1"
    assert small.equations()[1] == "prior + 0.400 x2 - 0.400 x1^2 x2"
    samples = coef + np.array([-3.1e-5, 3.1e-5])[:, None, None]   # std 4.38e-05
    spread = CoefficientUncertainty(coef, samples, small.state_names_,
                                    small.get_feature_names(), 1)
    assert small.equations(uncertainty=spread)[0] == "prior - (1.95e-04 ± 4.38e-05) x1"
    assert exact_model.coefficients().shape == (2, 10)


def test_simulate_matches_the_true_hybrid_system(exact_model, vdp_validation):
    sim = exact_model.simulate(vdp_validation.x[0], vdp_validation.t)
    assert sim.shape == vdp_validation.x.shape
    np.testing.assert_allclose(sim, vdp_validation.x, atol=1e-6)
    score = exact_model.score(vdp_validation.x, t=vdp_validation.t, metric="trajectory")
    assert score < 1e-6
    # the prior alone is far off on the same validation run
    prior_only = dc.DiscrepancyModel(prior=prior_parameter,
                                     feature_library=dc.PolynomialLibrary(degree=1),
                                     optimizer=dc.STLSQ(threshold=1e9))
    with pytest.warns(UserWarning):
        prior_only.fit(vdp_validation.x, t=vdp_validation.dt, x_dot=prior_parameter(
            vdp_validation.x))
    off = prior_only.simulate(vdp_validation.x[0], vdp_validation.t)
    assert np.linalg.norm(off - vdp_validation.x) / np.linalg.norm(vdp_validation.x) > 0.1


def test_noisy_fit_simulates_within_one_percent(vdp_data, vdp_validation):
    model = dc.DiscrepancyModel(prior=prior_parameter,
                                feature_library=dc.CustomLibrary(expressions=PAPER_LIBRARY),
                                optimizer=dc.STLSQ(threshold=0.05),
                                differentiation_method=dc.SavitzkyGolay(window_length=21))
    model.fit(noisy(vdp_data, 0), t=vdp_data.dt)
    error = model.score(vdp_validation.x, t=vdp_validation.t, metric="trajectory")
    assert error < 0.01


def test_score_r2_on_exact_derivatives(exact_model, vdp_validation):
    assert exact_model.score(vdp_validation.x, t=vdp_validation.t,
                             x_dot=vdp_validation.x_dot) > 1 - 1e-12
    assert exact_model.score(vdp_validation.x, t=vdp_validation.t, x_dot=vdp_validation.x_dot,
                             metric="rmse") < 1e-9


@pytest.fixture(scope="module")
def forced_model(forced_data):
    t, x, uu = forced_data
    x_dot = forced_rhs(x, uu)
    model = dc.DiscrepancyModel(prior=forced_prior, feature_library=control_library(),
                                optimizer=dc.STLSQ(threshold=0.05))
    return model.fit(x, t=t, u=uu, x_dot=x_dot)


def test_simulate_with_inputs_matches_solve_ivp(forced_model, forced_data, helpers):
    t, x, uu = forced_data
    t, x, uu = t[:1001], x[:1001], uu[:1001]
    # callable input: the same law the data came from
    np.testing.assert_allclose(forced_model.simulate(x[0], t, u=u_of_t), x, atol=1e-7)
    # sampled input, linearly interpolated between samples: error O(dt^2)
    np.testing.assert_allclose(forced_model.simulate(x[0], t, u=uu), x, atol=1e-4)


def test_sympy_prior_gives_the_true_hybrid_model(vdp_data):
    model = dc.DiscrepancyModel(prior=SYMPY_PRIOR, feature_library=dc.PolynomialLibrary(degree=3),
                                optimizer=dc.STLSQ(threshold=0.05))
    model.fit(vdp_data.x, t=vdp_data.dt, x_dot=vdp_data.x_dot)
    hybrid = model.to_sympy()
    assert len(hybrid) == 2
    for got, true in zip(hybrid, TRUE_VDP, strict=True):
        difference = sp.Poly(sp.expand(got - true), x1, x2)
        assert max((abs(float(c)) for c in difference.coeffs()), default=0.0) < 1e-9
    discrepancy = model.to_sympy(part="discrepancy")
    assert discrepancy[0] == 0
    assert sp.Poly(discrepancy[1], x1, x2).as_dict().keys() == {(0, 1), (2, 1)}


def test_sympy_prior_noisy_data_within_one_percent(vdp_data):
    model = dc.DiscrepancyModel(prior=SYMPY_PRIOR,
                                feature_library=dc.CustomLibrary(expressions=PAPER_LIBRARY),
                                optimizer=dc.STLSQ(threshold=0.05),
                                differentiation_method=dc.SavitzkyGolay(window_length=21))
    model.fit(noisy(vdp_data, 1), t=vdp_data.dt)
    true = sp.Poly(sp.expand(TRUE_VDP[1]), x1, x2).as_dict()
    got = sp.Poly(sp.expand(model.to_sympy()[1]), x1, x2).as_dict()
    assert got.keys() == true.keys()
    for k, v in true.items():
        assert abs(float(got[k]) - float(v)) <= 0.01 * abs(float(v)), (k, got[k], v)


def test_sympy_and_callable_priors_give_the_same_coefficients(vdp_data):
    kw = dict(feature_library=dc.PolynomialLibrary(degree=3), optimizer=dc.STLSQ(threshold=0.05),
              differentiation_method="savitzky_golay")
    x = noisy(vdp_data, 2)
    a = dc.DiscrepancyModel(prior=SYMPY_PRIOR, **kw).fit(x, t=vdp_data.dt)
    b = dc.DiscrepancyModel(prior=prior_parameter, **kw).fit(x, t=vdp_data.dt)
    np.testing.assert_allclose(a.coefficients(), b.coefficients(), rtol=1e-10, atol=1e-12)


def test_state_and_input_names(forced_data):
    t, x, uu = forced_data
    lib = dc.FourierLibrary(variables=["angle"]) * dc.PolynomialLibrary(
        degree=1, include_bias=False, variables=["force"])
    model = dc.DiscrepancyModel(prior=forced_prior, feature_library=lib,
                                optimizer=dc.STLSQ(threshold=0.05),
                                differentiation_method=dc.SavitzkyGolay(window_length=11),
                                state_names=["angle", "rate"], input_names=["force"])
    model.fit(x, t=t, u=uu)
    assert_terms(model, {(1, "sin(angle) force"): GAIN})
    assert model.equations()[1] == "prior + 0.800 sin(angle) force"


def test_estimator_contract(vdp_data):
    lib, opt = dc.PolynomialLibrary(degree=3), dc.STLSQ(threshold=0.05)
    model = dc.DiscrepancyModel(prior=prior_parameter, feature_library=lib, optimizer=opt)
    assert model.feature_library is lib and model.optimizer is opt
    with pytest.raises(NotFittedError):
        model.predict(vdp_data.x)
    assert model.fit(vdp_data.x, t=vdp_data.dt) is model
    # the user's library and optimizer objects are not fitted in place
    assert not hasattr(lib, "feature_expressions_") and not hasattr(opt, "coef_")


def test_sampled_input_is_interpolated_linearly(forced_model, forced_data, helpers):
    t, x, uu = forced_data
    t, uu = t[:301:10], uu[:301:10]   # coarse samples, so the hold rule matters
    law = lambda tau: np.array([np.interp(tau, t, uu[:, 0])])  # noqa: E731
    reference = helpers.integrate(lambda s, v: forced_rhs(s, v)[0], x[0], t, u=law)
    np.testing.assert_allclose(forced_model.simulate(x[0], t, u=uu), reference, atol=1e-6)


def test_sampled_input_with_zero_order_hold(forced_model, forced_data, helpers):
    t, x, uu = forced_data
    t, uu = t[:301:10], uu[:301:10]
    # reference: one solve per interval with the input held at its left sample
    state, reference = x[0], [x[0]]
    for k in range(len(t) - 1):
        piece = helpers.integrate(lambda s, v, k=k: forced_rhs(s, uu[k])[0], state,
                                  np.array([t[k], t[k + 1]]))
        state = piece[-1]
        reference.append(state)
    sim = forced_model.simulate(x[0], t, u=uu, u_hold="zoh")
    np.testing.assert_allclose(sim, np.array(reference), atol=1e-6)
    # and the hold rule makes a visible difference
    assert np.max(np.abs(sim - forced_model.simulate(x[0], t, u=uu))) > 1e-3


def test_savitzky_golay_smoothed_states_feed_the_library(vdp_data):
    from scipy.signal import savgol_filter

    from discrepancy.data import as_trajectories

    x = noisy(vdp_data, 4)
    model = dc.DiscrepancyModel(prior=prior_parameter, feature_library=dc.PolynomialLibrary(3),
                                optimizer=dc.STLSQ(threshold=0.05),
                                differentiation_method=dc.SavitzkyGolay(window_length=21))
    model.fit(x, t=vdp_data.dt)
    (trajectory,) = as_trajectories(x, vdp_data.dt)
    z, y = model.residual(trajectory)
    smooth = savgol_filter(x, 21, 3, axis=0, mode="interp")
    slope = savgol_filter(x, 21, 3, deriv=1, delta=vdp_data.dt, axis=0, mode="interp")
    np.testing.assert_allclose(z, smooth, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(y, slope - prior_parameter(smooth), rtol=1e-10, atol=1e-10)


def test_prior_taking_only_x(vdp_data):
    kw = dict(feature_library=dc.PolynomialLibrary(degree=3), optimizer=dc.STLSQ(threshold=0.05))
    a = dc.DiscrepancyModel(prior=lambda x: prior_parameter(x), **kw).fit(
        vdp_data.x, t=vdp_data.dt, x_dot=vdp_data.x_dot)
    assert_terms(a, {(1, "x2"): 0.4, (1, "x1^2 x2"): -0.4}, rtol=1e-9)


def test_sympy_prior_with_inputs_exports_the_whole_hybrid(forced_data):
    import casadi as ca

    t, x, uu = forced_data
    model = dc.DiscrepancyModel(prior=[x2, -x1 - sp.Rational(1, 5) * x2],
                                feature_library=control_library(),
                                optimizer=dc.STLSQ(threshold=0.05))
    model.fit(x, t=t, u=uu, x_dot=forced_rhs(x, uu))
    hybrid = model.to_sympy()
    expected = -x1 - sp.Rational(1, 5) * x2 + GAIN * sp.sin(x1) * u
    residue = sp.expand(hybrid[1] - expected)
    assert all(abs(float(term.as_coeff_Mul()[0])) < 1e-9
               for term in sp.Add.make_args(residue)) or residue == 0
    f = model.to_casadi()
    rng = np.random.default_rng(1)
    xs, us = rng.uniform(-2, 2, size=(20, 2)), rng.uniform(-1, 1, size=(20, 1))
    got = np.vstack([np.asarray(f(a, b)).ravel() for a, b in zip(xs, us, strict=True)])
    np.testing.assert_allclose(got, forced_rhs(xs, us), atol=1e-9)
    assert isinstance(f, ca.Function)


_ARMED = {"on": False}


def _tripwire(v):
    if _ARMED["on"]:
        raise AssertionError("an inactive term was evaluated")
    return np.tanh(v)


def test_predict_and_simulate_evaluate_only_active_terms(vdp_data, vdp_validation):
    lib = dc.PolynomialLibrary(degree=3) + dc.CustomLibrary(functions={"trip": _tripwire})
    model = dc.DiscrepancyModel(prior=prior_parameter, feature_library=lib,
                                optimizer=dc.STLSQ(threshold=0.05))
    model.fit(vdp_data.x, t=vdp_data.dt, x_dot=vdp_data.x_dot)
    assert_terms(model, {(1, "x2"): 0.4, (1, "x1^2 x2"): -0.4}, rtol=1e-9)
    _ARMED["on"] = True
    try:
        model.predict(vdp_validation.x)
        model.discrepancy(vdp_validation.x)
        sim = model.simulate(vdp_validation.x[0], vdp_validation.t[:500])
    finally:
        _ARMED["on"] = False
    np.testing.assert_allclose(sim, vdp_validation.x[:500], atol=1e-6)


# ------------------------------------------------------------ the public seam

def test_statistics_of_trajectories_summed_equal_the_fit_of_their_list(vdp_data, helpers):
    """make_setup -> statistics per trajectory -> fit_statistics is the fit, piece by piece
    (the way streamed, distributed or incrementally updated fits use it)."""
    from discrepancy.data import as_trajectories

    x = vdp_data.x
    parts = [x[:900], x[900:1700], x[1700:]]
    model = dc.DiscrepancyModel(prior=helpers.vdp_rhs(0.1), feature_library=dc.PolynomialLibrary(3),
                                differentiation_method=dc.SavitzkyGolay(21))
    whole = clone(model).fit(parts, t=vdp_data.dt)
    # the same sample as the fit: its size sets the cross-validation segments
    setup = model.make_setup(2, 0, sample=as_trajectories(parts, vdp_data.dt))
    stats, summed = setup.new_statistics(), setup.new_statistics()
    for tr in as_trajectories(parts, vdp_data.dt):
        setup.statistics(tr, into=stats)     # rows numbered on, as a list's fit numbers them
        summed += setup.statistics(tr)       # each piece numbered from 0: same sums
    np.testing.assert_allclose(summed.gram, stats.gram, rtol=1e-12)
    np.testing.assert_allclose(summed.rhs, stats.rhs, rtol=1e-12)
    model.fit_statistics(stats, setup)
    np.testing.assert_allclose(model.coef_, whole.coef_, rtol=1e-12, atol=1e-14)
    assert model.statistics_.count == len(x)
    assert model.get_feature_names() == whole.get_feature_names()


def test_fit_statistics_refuses_statistics_of_another_set_up(vdp_data):
    model = dc.DiscrepancyModel(feature_library=dc.PolynomialLibrary(3))
    other = dc.DiscrepancyModel(feature_library=dc.PolynomialLibrary(2)).make_setup(2, 0)
    with pytest.raises(ShapeError, match="6 features.*has 10"):
        model.fit_statistics(other.new_statistics(), model.make_setup(2, 0))
    with pytest.raises(ParameterError, match="FitSetup"):
        model.fit_statistics(other.new_statistics(), "setup")


def test_a_state_named_like_an_input_is_refused(vdp_data):
    u = np.ones((len(vdp_data.x), 1))
    model = dc.DiscrepancyModel(state_names=["a", "b"], input_names=["a"])
    with pytest.raises(ParameterError, match=r"must not share names.*\['a'\]"):
        model.fit(vdp_data.x, t=vdp_data.dt, u=u)


def test_specs_are_accepted_for_library_optimizer_and_differentiation(vdp_data, helpers):
    spec = dc.DiscrepancyModel(prior=helpers.vdp_rhs(0.1), feature_library="poly(3)",
                               optimizer="stlsq(threshold=0.05)",
                               differentiation_method="savitzky_golay(window_length=21)")
    objects = dc.DiscrepancyModel(prior=helpers.vdp_rhs(0.1),
                                  feature_library=dc.PolynomialLibrary(3),
                                  optimizer=dc.STLSQ(threshold=0.05),
                                  differentiation_method=dc.SavitzkyGolay(21))
    a = spec.fit(vdp_data.x, t=vdp_data.dt).coef_
    b = objects.fit(vdp_data.x, t=vdp_data.dt).coef_
    np.testing.assert_array_equal(a, b)
    assert np.count_nonzero(a) == 2 and abs(a[1, 2] - 0.4) < 0.01  # truth: 0.4 x2


def test_arguments_after_t_must_be_named(vdp_data, exact_model):
    model = dc.DiscrepancyModel()
    with pytest.raises(ParameterError, match="must be passed by name.*PySINDy"):
        model.fit(vdp_data.x, vdp_data.dt, vdp_data.x_dot)
    x, dt, xd = vdp_data.x[:300], vdp_data.dt, vdp_data.x_dot[:300]
    calls = {"score": lambda: exact_model.score(x, dt, None, xd),
             "bootstrap": lambda: exact_model.bootstrap(x, dt, None),
             "simulate": lambda: exact_model.simulate(x[0], np.arange(5) * dt, None)}
    for name, call in calls.items():
        with pytest.raises(ParameterError, match=rf"{name}: arguments after t .* by name"):
            call()
    with pytest.raises(ParameterError, match=r"simulate\(x0, t, u=u\)") as info:
        calls["simulate"]()
    assert "x_dot" not in str(info.value)   # simulate takes no derivatives


@pytest.mark.parametrize(("t", "message"), [("1", "positive time step"),
                                             ("fast", "positive time step"),
                                             ([None, 0.01, 0.02], "finite.*row 0")])
def test_bad_times_are_named(vdp_data, t, message):
    x = vdp_data.x[:3] if isinstance(t, list) else vdp_data.x
    with pytest.raises(dc.errors.DataError, match=message):
        dc.DiscrepancyModel().fit(x, t=t)


# ------------------------------------------------------------ sample weights

def test_sample_weights_equal_numpy_weighted_least_squares(lorenz_data):
    x, xd = lorenz_data.x, lorenz_data.x_dot
    rng = np.random.default_rng(2)
    noisy = xd + rng.standard_normal(xd.shape)
    w = rng.uniform(0, 2, len(x))
    model = dc.DiscrepancyModel(feature_library=dc.PolynomialLibrary(2),
                                optimizer=dc.STLSQ(threshold=0.0)).fit(
        x, t=lorenz_data.dt, x_dot=noisy, sample_weight=w)
    theta = model.feature_library_.transform(x)
    root = np.sqrt(w)[:, None]
    expected = np.linalg.lstsq(theta * root, noisy * root, rcond=None)[0].T
    np.testing.assert_allclose(model.coef_, expected, rtol=1e-8, atol=1e-10)
    # streamed: the weights travel in the chunks and give the same model
    chunks = iter([dc.Chunk(x[i:i + 700], x_dot=noisy[i:i + 700], weight=w[i:i + 700])
                   for i in range(0, len(x), 700)])
    streamed = dc.DiscrepancyModel(feature_library=dc.PolynomialLibrary(2),
                                   optimizer=dc.STLSQ(threshold=0.0)).fit(chunks, t=lorenz_data.dt)
    np.testing.assert_allclose(streamed.coef_, expected, rtol=1e-8, atol=1e-10)


def test_a_weight_per_trajectory_and_zero_weight_drops_a_trajectory(lorenz_data):
    x, xd = lorenz_data.x, lorenz_data.x_dot
    wrong = -xd                                  # a trajectory that must not count
    model = dc.DiscrepancyModel(feature_library=dc.PolynomialLibrary(2),
                                optimizer=dc.STLSQ(threshold=0.5))
    model.fit([x, x], t=lorenz_data.dt, x_dot=[xd, wrong], sample_weight=[1.0, 0.0])
    assert model.coef_[0, 1:3] == pytest.approx([-10, 10], rel=1e-6)
    with pytest.raises(dc.errors.DataError, match="sample_weight must be >= 0"):
        model.fit(x, t=lorenz_data.dt, x_dot=xd, sample_weight=-np.ones(len(x)))
    with pytest.raises(ShapeError, match="sample_weight must have"):
        model.fit(x, t=lorenz_data.dt, x_dot=xd, sample_weight=np.ones(3))
