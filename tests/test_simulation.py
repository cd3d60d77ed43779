"""Bounded simulation: discontinuous terms, blow-ups and budgets against analytic truth."""
import numpy as np
import pytest
import sympy as sp

import discrepancy as dc
from discrepancy.errors import ParameterError, SimulationError
from discrepancy.models.simulate.simulation import integrate

X1, X2 = sp.symbols("x1 x2")


def coulomb_model(friction=0.5):
    """x1' = x2, x2' = -x1 - F sign(x2): the prior is the undamped oscillator, g the friction."""
    x = np.random.default_rng(0).normal(size=(400, 2))
    x_dot = np.c_[x[:, 1], -x[:, 0] - friction * np.sign(x[:, 1])]
    prior = [X2, -X1]
    lib = dc.CustomLibrary([sp.sign(X2), X1, X2])
    return dc.DiscrepancyModel(prior=prior, feature_library=lib,
                               optimizer=dc.STLSQ(threshold=0.05)).fit(x, t=1.0, x_dot=x_dot)


def coulomb_exact(t, x0, friction):
    """Closed form of x1 from rest at x0: each half swing is a harmonic arc about the
    friction's equilibrium (+F while moving left, -F while moving right), ending at the
    mirror point; the motion stops at a turning point with |x1| <= F."""
    out, start, t0 = np.empty_like(t), x0, 0.0
    for i, tau in enumerate(t):
        while abs(start) > friction and tau - t0 > np.pi:
            centre = friction if start > 0 else -friction
            start, t0 = 2 * centre - start, t0 + np.pi
        if abs(start) <= friction:
            out[i] = start
        else:
            centre = friction if start > 0 else -friction
            out[i] = centre + (start - centre) * np.cos(tau - t0)
    return out


@pytest.mark.timeout(60, method="signal")  # guards a hang, not speed
def test_learned_coulomb_friction_simulates_by_fixed_steps_and_matches_the_closed_form():
    model = coulomb_model(0.5)
    assert model.coef_[1, 0] == pytest.approx(-0.5, abs=1e-12)
    t = np.arange(0.0, 12.0, 0.01)
    x = model.simulate([3.0, 0.0], t)  # 3 -> -2 -> 1 -> 0, then at rest
    truth = coulomb_exact(t, 3.0, 0.5)
    assert np.max(np.abs(x[:, 0] - truth)) < 5e-3


@pytest.mark.timeout(60, method="signal")
def test_an_adaptive_method_on_a_discontinuous_model_stops_with_its_budget():
    model = coulomb_model(0.5)
    t = np.arange(0.0, 12.0, 0.01)
    with pytest.raises(SimulationError, match="budget of 1000 right-hand-side") as info:
        model.simulate([3.0, 0.0], t, method="RK45", max_evaluations=1000)
    err = info.value
    assert err.partial.shape[1] == 2 and len(err.partial) == len(err.times) < len(t)
    truth = coulomb_exact(err.times, 3.0, 0.5)
    assert np.max(np.abs(err.partial[:, 0] - truth)) < 1e-3  # what it did compute is right


def test_rk4_on_a_linear_system_converges_at_fourth_order():
    t = np.linspace(0.0, 2.0, 11)
    errors = []
    for substeps in (2, 4):
        x = integrate(lambda x, u: -x, [1.0], t, n_states=1, n_inputs=0, method="rk4",
                      substeps=substeps)
        errors.append(np.max(np.abs(x[:, 0] - np.exp(-t))))
    assert 12 < errors[0] / errors[1] < 20  # 2^4 = 16


@pytest.mark.parametrize("kws, name", [({"method": "bogus"}, "method"), ({"atol": -1}, "atol"),
                                       ({"rtol": float("nan")}, "rtol"),
                                       ({"substeps": 0}, "substeps"),
                                       ({"max_evaluations": 0}, "max_evaluations")])
def test_bad_integrator_options_are_named(kws, name):
    with pytest.raises(ParameterError, match=name):
        integrate(lambda x, u: -x, [1.0], np.linspace(0, 1, 5), n_states=1, n_inputs=0, **kws)
