"""Energy discrepancy: the dissipation form recovers known friction laws; the paper's state
form is a tautology."""
import warnings

import numpy as np
import pytest
import sympy as sp

import discrepancy as dc
from discrepancy.energy import (
    DissipationDiscrepancy,
    EnergyDiscrepancy,
    EnergyTautologyWarning,
    default_friction_library,
    energy_span_residual,
    fit_dissipation,
    integrated_powers,
    percent_error,
    support_loss_terms,
)
from discrepancy.errors import NotFittedError, ParameterError, ShapeError
from discrepancy.symbolic import symbol
from discrepancy.systems import DoublePendulum, DoublePendulumParameters

SPEEDS = ["dphi1", "dphi2"]


def pendulum_terms(**kwargs):
    """The default laws for the double pendulum's joints (the elbow turns at dphi1 - dphi2)."""
    return default_friction_library(SPEEDS, joints=DoublePendulum().joints(), **kwargs)


def dissipation(pend, **kwargs):
    kwargs.setdefault("friction_terms", pendulum_terms())
    return DissipationDiscrepancy(pend.energy, position_names=["phi1", "phi2"], **kwargs)


def state_form(pend, library):
    return EnergyDiscrepancy(pend.energy, feature_library=library,
                             position_names=["phi1", "phi2"],
                             optimizer=dc.STLSQ(threshold=1e-5, alpha=0.0))


@pytest.fixture(scope="module")
def swings():
    """Two exact swings (5 s, 1 kHz) of the Table-1 pendulum from different energies."""
    pend = DoublePendulum()
    t = np.arange(5001) / 1000
    return pend, t, [pend.simulate(x0, t) for x0 in ([2.0, 4.0, 0, 0], [1.8, 2.5, 0, 0])]


def test_percent_error_by_hand():
    dh = np.array([0.0, 1.0, 2.0, 4.0])
    model = np.array([0.0, 1.5, 2.0, 3.0])
    np.testing.assert_allclose(percent_error(dh, model), [0, -12.5, 0, 25])
    np.testing.assert_allclose(percent_error(dh + 10, model + 10, normaliser="range"),
                               [0, -12.5, 0, 25])


def test_integrated_powers_of_constant_speeds():
    terms = pendulum_terms()
    t = np.linspace(0, 2, 201)
    v = np.tile([3.0, 1.0], (201, 1))     # joint 1 at 3 rad/s, joint 2 at 2 rad/s
    integral = integrated_powers(terms, v, t, SPEEDS)[-1]
    stribeck = [w * np.exp(-(w / v) ** 2) * 2 for w in (3.0, 2.0) for v in (0.1, 0.3, 1.0)]
    expected = [9 * 2, 4 * 2, 3 * 2, 2 * 2, 27 * 2, 1 * 2, *stribeck]
    np.testing.assert_allclose(integral, expected, rtol=1e-12, atol=1e-300)


TWO_LAWS = {"viscous joint 1": 7e-4, "Coulomb joint 2": 3e-4}


@pytest.fixture(scope="module")
def known_loss():
    """Velocities of a decaying two-frequency swing (30 s, 1 kHz), the default library's
    integrated powers along them, and the energy lost to the laws ``TWO_LAWS``."""
    t = np.arange(30001) / 1000
    decay = np.exp(-t / 15)
    v = np.column_stack([5 * decay * np.sin(4.1 * t), 7 * decay * np.sin(6.3 * t + 1)])
    terms = pendulum_terms()
    features = integrated_powers(terms, v, t, SPEEDS)
    index = {term.name: i for i, term in enumerate(terms)}
    return terms, features, sum(c * features[:, index[n]] for n, c in TWO_LAWS.items())


def _found(fit) -> dict[str, float]:
    return {term.name: c for term, c in zip(fit.terms, fit.coefficients, strict=True)}


def test_dissipation_fit_recovers_viscous_and_coulomb_laws(known_loss):
    terms, features, delta_h = known_loss
    fit = fit_dissipation(features, delta_h + 2e-3, terms)
    found = _found(fit)
    assert set(found) == set(TWO_LAWS)
    for name, value in TWO_LAWS.items():
        assert found[name] == pytest.approx(value, rel=1e-6)
    assert fit.offset == pytest.approx(2e-3, rel=1e-6)


def test_block_fit_survives_pointwise_noise_of_the_energy(known_loss):
    """White noise of 0.3 mJ on dH, where a 2 s block loses 0.8 mJ at the end: losses taken
    between single samples at the block edges were off by 35 % (Coulomb); between block means
    the known laws come back within 1 %."""
    terms, features, delta_h = known_loss
    noisy = delta_h + np.random.default_rng(0).normal(0, 3e-4, len(delta_h))
    found = _found(fit_dissipation(features, noisy, terms, block=2000))
    assert set(found) == set(TWO_LAWS)
    for name, value in TWO_LAWS.items():
        assert found[name] == pytest.approx(value, rel=0.01)


def test_learned_dissipation_is_never_negative():
    """A loss whose best unconstrained fit needs a negative Coulomb coefficient (energy fed
    in at joint 1): the law keeps only dissipating terms, with positive coefficients, and
    the energy it says is lost never decreases."""
    t = np.arange(5001) / 1000
    v = np.column_stack([np.sin(3 * t), np.cos(2 * t)])
    terms = pendulum_terms()
    features = integrated_powers(terms, v, t, SPEEDS)
    free = np.linalg.lstsq(np.c_[np.ones(len(t)), features[:, [0, 2]]],
                           8e-4 * features[:, 0] - 2e-4 * features[:, 2], rcond=None)[0]
    assert free[2] < 0                      # least squares would pump energy in
    fit = fit_dissipation(features, 8e-4 * features[:, 0] - 2e-4 * features[:, 2], terms)
    assert len(fit.terms) >= 1 and np.all(fit.coefficients > 0)
    law = features[:, [terms.index(term) for term in fit.terms]] @ fit.coefficients
    assert np.all(np.diff(law) >= -1e-15)


def test_energy_discrepancy_recovers_k1_k2_from_exact_states(swings):
    pend, t, (x, _) = swings
    model = dissipation(pend).fit(x[:, :2], t, dq=x[:, 2:])
    found = {term.name: c for term, c in zip(model.terms_, model.coef_, strict=True)}
    p = DoublePendulumParameters()
    assert set(found) == {"viscous joint 1", "viscous joint 2"}
    assert found["viscous joint 1"] == pytest.approx(p.k1, rel=1e-4)
    assert found["viscous joint 2"] == pytest.approx(p.k2, rel=1e-4)
    assert "N m s" in model.equation()
    score = model.score(x[:, :2], t, dq=x[:, 2:], start=model.offset_)
    assert score["max_abs_percent_of_max"] < 0.01


def _libraries():
    phi1, phi2, d1, d2 = (symbol(n) for n in ("phi1", "phi2", "dphi1", "dphi2"))
    paper = dc.PolynomialLibrary(degree=3) + dc.FourierLibrary(n_frequencies=1)
    spans = paper + dc.CustomLibrary(expressions=[sp.cos(phi1 - phi2) * d1 * d2])
    return paper, spans


def test_state_form_spanning_library_is_a_tautology(swings):
    """Spanning H_m: exact on training, wrong by E0 - E0' on a swing from another energy."""
    pend, t, (x, x_other) = swings
    _, spans = _libraries()
    model = state_form(pend, spans)
    with pytest.warns(EnergyTautologyWarning, match="spans the model energy"):
        model.fit(x[:, :2], t, dq=x[:, 2:])
    assert model.span_residual_ < 1e-8
    train = model.score(x[:, :2], t, dq=x[:, 2:])
    assert train["max_abs_percent_of_max"] < 1e-3
    other = model.predict(x_other[:, :2], t, dq=x_other[:, 2:])
    truth = model.measured_delta_h(x_other)
    e0_gap = pend.energy(x[:1])[0] - pend.energy(x_other[:1])[0]
    np.testing.assert_allclose(other - truth, e0_gap, atol=1e-6 * abs(e0_gap) + 1e-9)


def test_state_form_without_span_does_not_warn(swings):
    pend, t, (x, _) = swings
    paper, _ = _libraries()
    theta = paper.fit(["phi1", "phi2", "dphi1", "dphi2"]).transform(x)
    assert energy_span_residual(theta, pend.energy(x)) > 1e-3
    model = state_form(pend, paper)
    with warnings.catch_warnings():
        warnings.simplefilter("error", EnergyTautologyWarning)
        model.fit(x[:, :2], t, dq=x[:, 2:])


def test_bad_use_raises_clear_errors(swings):
    pend, t, (x, _) = swings
    with pytest.raises(NotFittedError):
        dissipation(pend).predict(x[:, :2], t, dq=x[:, 2:])
    with pytest.raises(ParameterError, match="feature_library"):
        EnergyDiscrepancy(pend.energy).fit(x[:, :2], t, dq=x[:, 2:])
    with pytest.raises(ShapeError, match="energy"):
        dissipation(pend).set_params(energy=lambda z: np.zeros(3)).fit(x[:, :2], t,
                                                                      dq=x[:, 2:])
    with pytest.raises(ShapeError, match="position_names"):
        dissipation(pend).fit(x[:, :3], t)
    with pytest.raises(ParameterError, match="max_terms"):
        dissipation(pend, max_terms=0).fit(x[:, :2], t, dq=x[:, 2:])
    with pytest.raises(ParameterError, match="energy"):
        DissipationDiscrepancy("H").fit(x[:, :2], t, dq=x[:, 2:])


def test_max_terms_larger_than_the_library_is_clipped(swings):
    pend, t, (x, _) = swings
    two = pendulum_terms()[:2]
    model = dissipation(pend, friction_terms=two, max_terms=20).fit(x[:, :2], t, dq=x[:, 2:])
    assert [term.name for term in model.terms_] == ["viscous joint 1", "viscous joint 2"]


def test_smoothed_coulomb_power():
    terms = pendulum_terms(coulomb_smoothing=0.5)
    coulomb = [t for t in terms if t.name == "Coulomb joint 1"][0]
    t = np.linspace(0, 1, 101)
    v = np.tile([2.0, 2.0], (101, 1))
    value = integrated_powers([coulomb], v, t, SPEEDS)[-1, 0]
    assert value == pytest.approx(2.0 * np.tanh(4.0), rel=1e-12)
    with pytest.raises(ParameterError, match="coulomb_smoothing"):
        pendulum_terms(coulomb_smoothing=0.0)


def test_support_loss_terms_integrate_the_squared_dynamic_pivot_force(swings):
    pend, t, (x, _) = swings
    p = pend.parameters
    weight = (p.m1 + p.m2) * p.g
    terms = support_loss_terms(pend.pivot_force, pend.state_names, static_vertical=weight)
    names = ["phi1", "phi2", "dphi1", "dphi2"]
    got = integrated_powers(terms, x, t, names)[-1]
    force = pend.pivot_force(x)
    expected = [np.trapezoid(force[:, 0] ** 2, t), np.trapezoid((force[:, 1] - weight) ** 2, t)]
    np.testing.assert_allclose(got, expected, rtol=1e-12)
    # a fit with these terms in the library still finds the true joint friction
    model = dissipation(pend, friction_terms=(*pendulum_terms()[:4], *terms)).fit(
        x[:, :2], t, dq=x[:, 2:])
    coef = {term.name: c for term, c in zip(model.terms_, model.coef_, strict=True)}
    assert set(coef) == {"viscous joint 1", "viscous joint 2"}
    assert coef["viscous joint 1"] == pytest.approx(p.k1, rel=1e-3)


def test_bootstrap_intervals_cover_the_true_friction_and_shrink_with_less_noise(swings):
    pend, t, (x, _) = swings
    p = pend.parameters
    rng = np.random.default_rng(3)
    widths = []
    for noise in (3e-4, 3e-5):
        q = x[:, :2] + rng.normal(0, noise, x[:, :2].shape)
        model = dissipation(pend, max_terms=2,
                            differentiation_method=dc.SavitzkyGolay(51, 3)).fit(q, t)
        assert [term.name for term in model.terms_] == ["viscous joint 1", "viscous joint 2"]
        unc = model.bootstrap(q, t, n_resamples=100, seed=1)
        low, high = unc.interval()
        assert np.all(low[0] <= [p.k1, p.k2]) and np.all([p.k1, p.k2] <= high[0])
        widths.append(high[0] - low[0])
    assert np.all(widths[1] < 0.8 * widths[0])    # smoothing bias remains at low noise


def test_bootstrap_refuses_what_it_cannot_do(swings):
    pend, t, (x, _) = swings
    model = dissipation(pend)
    with pytest.raises(NotFittedError):
        model.bootstrap(x[:, :2], t, dq=x[:, 2:])
    model.fit(x[:, :2], t, dq=x[:, 2:])
    with pytest.raises(ParameterError, match="block_seconds"):
        model.bootstrap(x[:, :2], t, dq=x[:, 2:], block_seconds=0.0)
    with pytest.raises(ParameterError, match="at least 4 blocks"):
        model.bootstrap(x[:, :2], t, dq=x[:, 2:], block_seconds=3.0)
    with pytest.raises(ParameterError, match="n_resamples"):
        model.bootstrap(x[:, :2], t, dq=x[:, 2:], n_resamples=1)


def test_forecast_band_holds_the_true_energy_loss_and_narrows_with_less_noise(swings):
    """The band of dH on the second swing (another energy; exact dH = E0 - H_m from the
    noise-free states), and of the first swing's fit continued against the noise-free part
    of what it forecasts: the measured dH = E0 (noisy sample) - H_m(smoothed states), whose
    smoothing bias, a constant offset measured here against the exact states, the fit's
    offset absorbs."""
    pend, t, (x, x_new) = swings
    rng = np.random.default_rng(4)
    widths = []
    for noise in (3e-4, 3e-5):
        q, q_new = (s[:, :2] + rng.normal(0, noise, s[:, :2].shape) for s in (x, x_new))
        model = dissipation(pend, max_terms=2,
                            differentiation_method=dc.SavitzkyGolay(51, 3)).fit(q, t)
        unc = model.bootstrap(q, t, n_resamples=100, seed=1)
        edge = 25
        exact_new = pend.energy(x_new[:1])[0] - pend.energy(x_new[edge:-edge])
        low, high = model.predict_interval(q_new, t, unc)
        assert np.mean((low <= exact_new) & (exact_new <= high)) > 0.9
        smoothing_bias = np.mean(pend.energy(model.states(q, t)[0]) - pend.energy(x[edge:-edge]))
        exact_fit = model.e0_ - pend.energy(x[edge:-edge]) - smoothing_bias
        low_c, high_c = model.predict_interval(q, t, unc, continued=True)
        assert np.mean((low_c <= exact_fit) & (exact_fit <= high_c)) > 0.8   # pointwise 95 %
        widths.append(np.max(high - low))
    assert widths[1] < 0.5 * widths[0]


def test_forecast_band_refuses_a_foreign_uncertainty_and_a_bad_level(swings):
    pend, t, (x, x_new) = swings
    model = dissipation(pend, max_terms=2).fit(x[:, :2], t, dq=x[:, 2:])
    unc = model.bootstrap(x[:, :2], t, dq=x[:, 2:], n_resamples=10)
    other = dissipation(pend, max_terms=1).fit(x[:, :2], t, dq=x[:, 2:])
    with pytest.raises(ParameterError, match="this model's bootstrap"):
        other.predict_interval(x_new[:, :2], t, unc, dq=x_new[:, 2:])
    with pytest.raises(ParameterError, match="level"):
        model.predict_interval(x_new[:, :2], t, unc, dq=x_new[:, 2:], level=95)
