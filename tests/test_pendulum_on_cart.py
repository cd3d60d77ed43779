"""Single pendulum on a cart: the sympy-derived equations against a hand-written form,
energy conservation, and the flawed prior's exact discrepancy."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from discrepancy.control import as_casadi
from discrepancy.errors import ParameterError, ShapeError
from discrepancy.symbolic import compile_numpy
from discrepancy.systems import PendulumOnCart, PendulumOnCartParameters


def textbook(x, u, p):
    """(I + m a²) φ'' = m a (g sin φ - gain u cos φ) - k φ', s'' = gain u."""
    phi, _, dphi, ds = x.T
    acc = (p.m * p.a * (p.g * np.sin(phi) - p.gain * u[:, 0] * np.cos(phi)) - p.k * dphi) \
        / (p.I + p.m * p.a ** 2)
    return np.column_stack([dphi, ds, acc, p.gain * u[:, 0]])


def test_equations_match_the_textbook_form_for_any_parameters():
    rng = np.random.default_rng(0)
    x = np.column_stack([rng.uniform(-np.pi, np.pi, 50), rng.normal(size=(50, 3))])
    u = rng.normal(0, 5, (50, 1))
    for p in (PendulumOnCartParameters(), PendulumOnCartParameters(m=0.4, a=0.3, k=0.01,
                                                                    gain=1.3)):
        system = PendulumOnCart(p)
        np.testing.assert_allclose(system.rhs(x, u), textbook(x, u, p), rtol=1e-12, atol=1e-12)
        f = as_casadi(system.equations())
        np.testing.assert_allclose(np.array(f.map(50)(x.T, u.T)).T, textbook(x, u, p),
                                   rtol=1e-12, atol=1e-12)
    states, inputs, parameters, rhs = PendulumOnCart.parametric_equations()
    names = [s.name for s in [*states, *inputs, *parameters]]
    p = PendulumOnCartParameters(m=0.3, I=0.004)
    z = np.hstack([x, u, np.tile([getattr(p, s.name) for s in parameters], (50, 1))])
    values = np.column_stack([compile_numpy(e, names)(z) for e in rhs])
    np.testing.assert_allclose(values, textbook(x, u, p), rtol=1e-12, atol=1e-12)


def test_frictionless_swinging_with_the_cart_at_rest_conserves_energy():
    system = PendulumOnCart(PendulumOnCartParameters(k=0.0))
    sol = solve_ivp(lambda t, x: system.rhs(x[None])[0], (0, 4), [2.5, 0.0, 1.0, 0.0],
                    method="DOP853", rtol=1e-12, atol=1e-12, dense_output=True)
    x = sol.sol(np.linspace(0, 4, 300)).T
    energy = system.energy(x)
    assert np.ptp(x[:, 0]) > 1.0   # a large swing
    assert np.max(np.abs(energy - energy[0])) < 1e-9


def test_the_flawed_prior_differs_by_friction_and_motor_gain_only():
    system = PendulumOnCart()
    p = system.parameters
    rng = np.random.default_rng(2)
    x, u = rng.normal(size=(30, 4)), rng.normal(size=(30, 1))
    flawed = as_casadi(system.flawed_equations())
    prior = np.array(flawed.map(30)(x.T, u.T)).T
    wrong = PendulumOnCartParameters(k=0.0, gain=1.5)
    np.testing.assert_allclose(prior, textbook(x, u, wrong), rtol=1e-12, atol=1e-12)
    g = as_casadi((*system.equations()[:2], system.discrepancy_equations()))
    np.testing.assert_allclose(np.array(g.map(30)(x.T, u.T)).T,
                               textbook(x, u, p) - textbook(x, u, wrong), atol=1e-12)
    with pytest.raises(ShapeError, match="x must be"):
        system.rhs(np.zeros((2, 6)))
    with pytest.raises(ParameterError, match="unknown"):
        p.scaled({"mass": 1.1})
    with pytest.raises(ParameterError, match="motor_error"):
        PendulumOnCart(motor_error=-2.0).flawed_equations()
    assert system.points(np.array([[0.0, 0.2, 0, 0]]))[0, 1] == pytest.approx([0.2, p.l])
