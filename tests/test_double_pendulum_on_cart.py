"""Double pendulum on a cart: conservation, power balance, an independent textbook form."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from discrepancy.errors import ParameterError, ShapeError
from discrepancy.symbolic import compile_numpy
from discrepancy.systems.double_pendulum_on_cart import (
    CartPendulumParameters,
    DoublePendulumOnCart,
)

P = CartPendulumParameters()


def random_states(rng, m):
    x = np.column_stack([rng.uniform(-np.pi, np.pi, (m, 2)), rng.uniform(-0.5, 0.5, m),
                         rng.normal(0, 3, (m, 2)), rng.normal(0, 1, m)])
    return x, rng.normal(0, 5, (m, 1))


def textbook_accelerations(x, u, p=P):
    """Hand-written equations of a compound double pendulum on an accelerating base."""
    p1, p2, _, d1, d2, _ = x.T
    u = u[:, 0]
    m11 = p.I1 + p.m1 * p.a1 ** 2 + p.m2 * p.l1 ** 2
    m12 = p.m2 * p.l1 * p.a2 * np.cos(p1 - p2)
    m22 = p.I2 + p.m2 * p.a2 ** 2
    b1 = ((p.m1 * p.a1 + p.m2 * p.l1) * (p.g * np.sin(p1) - u * np.cos(p1))
          - p.m2 * p.l1 * p.a2 * np.sin(p1 - p2) * d2 ** 2 - p.k1 * d1 + p.k2 * (d2 - d1))
    b2 = (p.m2 * p.a2 * (p.g * np.sin(p2) - u * np.cos(p2))
          + p.m2 * p.l1 * p.a2 * np.sin(p1 - p2) * d1 ** 2 - p.k2 * (d2 - d1))
    acc = np.linalg.solve(np.stack([np.stack([m11 + 0 * p1, m12], -1),
                                    np.stack([m12, m22 + 0 * p1], -1)], -2),
                          np.stack([b1, b2], -1)[..., None])
    return acc[..., 0]


def test_matches_textbook_equations_with_and_without_cart_motion():
    rng = np.random.default_rng(1)
    x, u = random_states(rng, 200)
    f = DoublePendulumOnCart().rhs(x, u)
    np.testing.assert_allclose(f[:, 3:5], textbook_accelerations(x, u), rtol=1e-10, atol=1e-10)
    np.testing.assert_array_equal(f[:, :3], x[:, 3:])
    np.testing.assert_array_equal(f[:, 5], u[:, 0])
    locked = DoublePendulumOnCart().rhs(np.column_stack([x[:, :5], 0 * x[:, 5]]), 0 * u)
    np.testing.assert_allclose(locked[:, 3:5], textbook_accelerations(x, 0 * u), rtol=1e-10,
                               atol=1e-10)


def test_locked_cart_matches_mounted_pendulum_if_available():
    try:
        from discrepancy.systems import DoublePendulum
        mounted = DoublePendulum()
    except (ImportError, AttributeError, ModuleNotFoundError):
        pytest.skip("mounted DoublePendulum not available")
    rng = np.random.default_rng(2)
    x, _ = random_states(rng, 50)
    x[:, 2] = 0
    x[:, 5] = 0
    cart = DoublePendulumOnCart().rhs(x, np.zeros((50, 1)))
    four = mounted.rhs(x[:, [0, 1, 3, 4]])
    np.testing.assert_allclose(cart[:, [0, 1, 3, 4]], four, rtol=1e-9, atol=1e-9)


def test_hanging_and_upright_are_equilibria():
    f = DoublePendulumOnCart().rhs(np.array([[np.pi, np.pi, 0.3, 0, 0, 0], [0, 0, 0, 0, 0, 0.0]]))
    np.testing.assert_allclose(f, 0, atol=1e-12)


def test_frictionless_unforced_motion_conserves_energy():
    system = DoublePendulumOnCart(CartPendulumParameters(k1=0.0, k2=0.0))
    x0 = np.array([2.0, -1.0, 0.1, 0.5, -2.0, 0.0])
    sol = solve_ivp(lambda t, x: system.rhs(x[None])[0], (0, 5), x0, method="DOP853",
                    rtol=1e-12, atol=1e-12, dense_output=True)
    x = sol.sol(np.linspace(0, 5, 400)).T
    energy = system.energy(x)
    assert np.ptp(x[:, 0]) > 1.0  # the motion is large
    assert np.max(np.abs(energy - energy[0])) < 1e-8 * (1 + abs(energy[0]))


def test_power_balance_at_random_states():
    """dH/dt = -dissipation + F ds, with F the horizontal force the cart puts on the links,
    found from Newton's law on the centres of mass (independent of the Lagrangian)."""
    rng = np.random.default_rng(3)
    system = DoublePendulumOnCart()
    x, u = random_states(rng, 100)
    f = system.rhs(x, u)
    h = 1e-6
    dH = (system.energy(x + h * f) - system.energy(x - h * f)) / (2 * h)
    p1, p2, _, d1, d2, ds = x.T
    dd1, dd2 = f[:, 3], f[:, 4]
    ax1 = u[:, 0] + P.a1 * (np.cos(p1) * dd1 - np.sin(p1) * d1 ** 2)
    ax2 = (u[:, 0] + P.l1 * (np.cos(p1) * dd1 - np.sin(p1) * d1 ** 2)
           + P.a2 * (np.cos(p2) * dd2 - np.sin(p2) * d2 ** 2))
    power_in = (P.m1 * ax1 + P.m2 * ax2) * ds
    expected = -system.dissipated_power(x) + power_in
    np.testing.assert_allclose(dH, expected, rtol=1e-6, atol=1e-6)
    assert np.max(np.abs(expected)) > 1.0


def test_energy_has_the_paper_potential():
    x = np.array([[0.0, 0.0, 0.0, 0, 0, 0], [np.pi, np.pi, 0.0, 0, 0, 0]])
    e = DoublePendulumOnCart().energy(x)
    v = P.g * (P.m1 * P.a1 + P.m2 * (P.l1 + P.a2))
    np.testing.assert_allclose(e, [v, -v], rtol=1e-12)


def test_flawed_model_and_sympy_forms():
    rng = np.random.default_rng(4)
    system = DoublePendulumOnCart()
    x, u = random_states(rng, 30)
    gap = system.rhs(x, u) - system.flawed_model()(x, u)
    expected = np.zeros_like(x)
    expected[:, 0] = -np.sin(x[:, 0])
    expected[:, 5] = 0.05 * u[:, 0]
    np.testing.assert_allclose(gap, expected, atol=1e-12)
    z = np.hstack([x, u])
    for getter, numeric in [(system.equations, system.rhs),
                            (system.flawed_equations, system.flawed_model())]:
        states, inputs, exprs = getter()
        names = [s.name for s in [*states, *inputs]]
        assert names == ["phi1", "phi2", "s", "dphi1", "dphi2", "ds", "u"]
        values = np.column_stack([compile_numpy(e, names)(z) for e in exprs])
        np.testing.assert_allclose(values, numeric(x, u), rtol=1e-11, atol=1e-11)


def test_bad_input_is_rejected():
    system = DoublePendulumOnCart()
    with pytest.raises(ShapeError, match="x must be"):
        system.rhs(np.zeros((3, 4)))
    with pytest.raises(ShapeError, match="u must be"):
        system.rhs(np.zeros((3, 6)), np.zeros((2, 1)))
    with pytest.raises(ParameterError, match="m1"):
        CartPendulumParameters(m1=-1.0)
    with pytest.raises(ParameterError, match="unknown"):
        P.scaled({"mass": 1.1})
    assert P.scaled({"m1": 1.02}).m1 == pytest.approx(0.2704 * 1.02)


def test_parametric_equations_match_a_perturbed_system():
    params = P.scaled({"m1": 1.02, "a2": 0.99, "I1": 1.015, "k2": 0.98})
    states, inputs, parameters, rhs = DoublePendulumOnCart.parametric_equations()
    names = [s.name for s in [*states, *inputs, *parameters]]
    rng = np.random.default_rng(5)
    x, u = random_states(rng, 40)
    z = np.hstack([x, u, np.tile([getattr(params, p.name) for p in parameters], (40, 1))])
    values = np.column_stack([compile_numpy(e, names)(z) for e in rhs])
    np.testing.assert_allclose(values[:, 3:5], textbook_accelerations(x, u, params), rtol=1e-10,
                               atol=1e-10)


def test_motor_gain_scales_the_cart_acceleration_everywhere():
    rng = np.random.default_rng(7)
    x, u = random_states(rng, 30)
    system = DoublePendulumOnCart(CartPendulumParameters(gain=1.3))
    f = system.rhs(x, u)
    np.testing.assert_allclose(f[:, 3:5], textbook_accelerations(x, 1.3 * u), rtol=1e-10,
                               atol=1e-10)
    np.testing.assert_allclose(f[:, 5], 1.3 * u[:, 0])
    states, inputs, parameters, rhs = DoublePendulumOnCart.parametric_equations()
    names = [s.name for s in [*states, *inputs, *parameters]]
    z = np.hstack([x, u, np.tile([getattr(system.parameters, p.name) for p in parameters],
                                 (30, 1))])
    values = np.column_stack([compile_numpy(e, names)(z) for e in rhs])
    np.testing.assert_allclose(values, f, rtol=1e-10, atol=1e-10)
