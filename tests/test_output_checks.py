"""Output-error fits judged by held-out forecasts: the prior alone flagged when chosen,
fitted on purpose, and refine never worse than the model it starts from."""
import functools

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

import discrepancy as dc
from discrepancy.errors import PriorOnlyWarning, SelectionWarning

pytest.importorskip("casadi")

T = np.arange(801) * 0.05


def forcing(seed=1, width=20):
    rng = np.random.default_rng(seed)
    return 2 * np.convolve(rng.standard_normal(len(T)), np.ones(width) / width, mode="same")


@functools.cache
def record(damping, cubic, push=0.0, until=0.0, seed=1):
    """x'' = -x - damping x' - cubic x^3 + u + push (the push until ``until``, unmeasured).
    Simulated once per set of arguments (several tests share a record), read-only."""
    u = forcing(seed)
    law = lambda s: np.interp(s, T, u) + (push if s < until else 0.0)  # noqa: E731
    x = solve_ivp(lambda s, z: [z[1], -z[0] - damping * z[1] - cubic * z[0] ** 3 + law(s)],
                  (0, T[-1]), [0.5, -0.3], t_eval=T, rtol=1e-11, atol=1e-11,
                  max_step=0.05).y.T
    y = x[:, 0] + 0.005 * np.random.default_rng(seed + 1).standard_normal(len(T))
    for array in (u, x, y):
        array.flags.writeable = False
    return u, x, y


def model(**kw):
    pos, vel, u = sp.symbols("pos vel u", real=True)
    return dc.DiscrepancyModel(prior=[vel, -pos - 0.1 * vel + u], state_names=["pos", "vel"],
                               input_names=["u"],
                               constraints=dc.Constraints(exact_equations=["pos"]), **kw)


def test_an_exact_prior_by_output_error_is_the_prior_alone_and_flagged():
    u, x, y = record(0.1, 0.0)
    with pytest.warns(PriorOnlyWarning, match="prior alone"):
        fitted = model(feature_library=dc.PolynomialLibrary(3, variables=["pos", "vel"])
                       ).fit_outputs(y, t=T, u=u, outputs=["pos"], progress=False)
    assert fitted.prior_only_ and not np.any(fitted.coef_)
    assert fitted.output_selection_[-1].n_terms == 0


def test_the_prior_alone_fitted_on_purpose_estimates_only_initial_states():
    u, x, y = record(0.1, 0.0)
    fitted = model(optimizer="prior_only").fit_outputs(y, t=T, u=u, outputs=["pos"])
    assert fitted.prior_only_ and fitted.output_selection_ == []
    np.testing.assert_allclose(fitted.x0_, x[0], atol=0.02)
    assert fitted.region_ is not None and fitted.region_.names == ("pos", "vel", "u")


def test_refine_of_the_prior_alone_says_it_has_no_terms_to_refit():
    u, x, y = record(0.1, 0.0)
    alone = model(optimizer="prior_only").fit(x, t=T, u=u)
    with pytest.warns(PriorOnlyWarning, match="has none .*fit_outputs"):
        alone.refine(y, t=T, u=u, outputs=["pos"])
    assert not np.any(alone.coef_)
    np.testing.assert_allclose(alone.x0_, x[0], atol=0.02)     # the exact prior's start


def test_prior_states_give_the_unmeasured_velocity_along_the_prior():
    """An exact prior with the position measured: its simulation from the fitted initial
    state recovers the velocity no output measures."""
    from discrepancy.models.outputs.output_checks import prior_states

    u, x, y = record(0.1, 0.0)
    states = prior_states(model(), y, T, u, outputs=["pos"])
    assert states.shape == x.shape
    assert np.sqrt(np.mean((states[:, 1] - x[:, 1]) ** 2)) < 0.02 * np.std(x[:, 1])


def true_model(u, x, coef_cubic=-0.5, coef_damping=-0.1):
    fitted = model(feature_library=dc.PolynomialLibrary(3, variables=["pos", "vel"]),
                   optimizer=dc.STLSQ(threshold=0.05)).fit(x, t=T, u=u)
    names = fitted.get_feature_names()
    coef = np.zeros_like(fitted.coef_)
    coef[1, names.index("pos^3")], coef[1, names.index("vel")] = coef_cubic, coef_damping
    return fitted.with_coefficients(coef)


def test_refine_keeps_coefficients_a_refit_would_spoil():
    """The truth's coefficients; the first 60 % of the record carries an unmeasured force
    that a refit absorbs into them; the clean rest is forecast worse by the refit."""
    u, x, y = record(0.2, 0.5, push=0.8, until=0.6 * T[-1])
    start = true_model(u, x)
    before = start.coef_.copy()
    with pytest.warns(SelectionWarning, match="kept the model's coefficients"):
        start.refine(y, t=T, u=u, outputs=["pos"])
    check = start.refine_check_
    assert check["kept_original"]
    assert check["heldout_error_refined"] > check["heldout_error_original"]
    np.testing.assert_array_equal(start.coef_, before)


def test_refine_improves_coefficients_that_are_off():
    u, x, y = record(0.2, 0.5)
    start = true_model(u, x, coef_cubic=-0.35, coef_damping=-0.15)
    start.refine(y, t=T, u=u, outputs=["pos"])
    assert not start.refine_check_["kept_original"]
    names = start.get_feature_names()
    assert start.coef_[1, names.index("pos^3")] == pytest.approx(-0.5, rel=0.03)


@pytest.mark.slow
def test_libraries_chosen_by_output_forecasts_find_the_hidden_cubic_spring():
    """Position measured only; the truth adds -0.1 vel - 0.5 pos^3 to the prior: among a
    linear and a cubic library (and the prior alone), the cubic one forecasts best."""
    u, x, y = record(0.2, 0.5)
    candidates = {"linear": dc.PolynomialLibrary(1, variables=["pos", "vel"]),
                  "cubic": dc.PolynomialLibrary(3, variables=["pos", "vel"])}
    choice = dc.choose_procedure(model(), y, t=T, u=u, outputs=["pos"], candidates=candidates,
                                 n_origins=2, fit_kws={"progress": False, "u_hold": "linear"},
                                 progress=False)
    assert choice.chosen == "cubic"
    assert choice.scores["prior alone"]["mean"] > 5 * choice.scores["cubic"]["mean"]
    names = choice.model.get_feature_names()
    assert choice.model.coef_[1, names.index("pos^3")] == pytest.approx(-0.5, rel=0.05)


def held_input_record(seed=5):
    """x'' = -x - 0.1 x' - 0.5 x^3 + u with u held constant over each sample interval (a
    zero-order hold, as a digital controller drives a plant), integrated exactly enough by
    20 RK4 steps per interval; position measured with noise 0.005."""
    rng = np.random.default_rng(seed)
    u = rng.uniform(-2, 2, len(T))
    x, h = np.array([0.5, -0.3]), (T[1] - T[0]) / 20
    f = lambda z, v: np.array([z[1], -z[0] - 0.1 * z[1] - 0.5 * z[0] ** 3 + v])  # noqa: E731
    states = [x]
    for v in u[:-1]:
        for _ in range(20):
            k1 = f(x, v)
            k2 = f(x + h / 2 * k1, v)
            k3 = f(x + h / 2 * k2, v)
            x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + f(x + h * k3, v))
        states.append(x)
    y = np.array(states)[:, 0] + 0.005 * rng.standard_normal(len(T))
    return u, y


@pytest.mark.slow
def test_a_held_input_is_recognised_by_output_forecasts():
    """The input is a step each sample: left to the procedure, the hold that forecasts
    best is the zero-order hold that drove the plant, and the cubic spring is found."""
    u, y = held_input_record()
    candidates = {"cubic": dc.PolynomialLibrary(3, variables=["pos", "vel"])}
    choice = dc.choose_procedure(model(), y, t=T, u=u, outputs=["pos"], candidates=candidates,
                                 fit_kws={"progress": False}, progress=False)
    assert choice.settings["u_hold"] == "zoh"
    assert choice.chosen == "cubic, u_hold=zoh"
    assert choice.scores["cubic"]["mean"] > 2 * choice.scores[choice.chosen]["mean"]
    names = choice.model.get_feature_names()
    assert choice.model.coef_[1, names.index("pos^3")] == pytest.approx(-0.5, rel=0.05)
