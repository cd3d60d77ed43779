"""Mounted double pendulum: energy conservation, power balance, and the rig's hand-written model."""
import numpy as np
import pytest
from scipy.integrate import cumulative_trapezoid
from scipy.io import savemat

from discrepancy.errors import DataError, ParameterError, ShapeError
from discrepancy.systems import DoublePendulum, DoublePendulumParameters

RIG = [0.093844, 0.137596, 0.108565, 0.116779, 0.172719, 4.3753e-4, 1.26883e-3, 2.37143e-4,
       1.0e-5, 9.80858]


def _frictionless():
    return DoublePendulum(DoublePendulumParameters(k1=0.0, k2=0.0))


def test_defaults_are_table_1():
    p = DoublePendulumParameters()
    assert (p.m1, p.m2, p.a1, p.a2, p.l1) == (0.2704, 0.2056, 0.1910, 0.1621, 0.2667)
    assert (p.I1, p.I2, p.k1, p.k2, p.g) == (0.003, 0.0011, 7.24e-4, 1.65e-4, 9.818)


def test_energy_at_rest_hanging_down_is_the_potential_minimum():
    p = DoublePendulumParameters()
    pend = DoublePendulum(p)
    x = np.array([[np.pi, np.pi, 0.0, 0.0]])
    expected = -p.g * (p.m1 * p.a1 + p.m2 * (p.l1 + p.a2))
    assert pend.energy(x)[0] == pytest.approx(expected, rel=1e-12)
    assert pend.kinetic_energy(x)[0] == pytest.approx(0.0, abs=1e-15)
    # kinetic energy of a rigid rotation of the first arm only: (I1 + m1 a1^2 + m2 l1^2) w^2/2
    # plus the second arm's translation with phi2 fixed
    w = 2.0
    t = pend.kinetic_energy(np.array([[1.0, 1.0, w, w]]))[0]
    rigid = 0.5 * w ** 2 * (p.I1 + p.m1 * p.a1 ** 2 + p.I2 + p.m2 * (p.l1 ** 2 + p.a2 ** 2
                                                                     + 2 * p.l1 * p.a2))
    assert t == pytest.approx(rigid, rel=1e-12)


def test_energy_is_conserved_without_friction():
    pend = _frictionless()
    t = np.linspace(0.0, 5.0, 2001)
    x = pend.simulate([2.0, 4.0, 0.0, 0.0], t)
    h = pend.energy(x)
    assert np.max(np.abs(h - h[0])) < 1e-8
    assert np.ptp(pend.kinetic_energy(x)) > 0.1   # it really swings


def test_power_balance_with_friction():
    pend = DoublePendulum()
    t = np.linspace(0.0, 5.0, 5001)
    x = pend.simulate([2.0, 4.0, 0.0, 0.0], t)
    h = pend.energy(x)
    lost = cumulative_trapezoid(pend.dissipated_power(x), t, initial=0.0)
    assert lost[-1] > 1e-2
    np.testing.assert_allclose(h[0] - h, lost, atol=1e-7 * abs(h[0]) + 1e-6 * lost[-1])
    # instantaneous: dH/dt = -(k1 w1^2 + k2 (w1 - w2)^2), from the gradient of H along rhs
    eps = 1e-6
    xs = x[::500]
    f = pend.rhs(xs)
    dh = (pend.energy(xs + eps * f) - pend.energy(xs - eps * f)) / (2 * eps)
    np.testing.assert_allclose(dh, -pend.dissipated_power(xs), rtol=1e-5, atol=1e-9)


def rig_residuals(p, x, a, k1, k2):
    """Residuals of the rig README's mounted model (typed independently of the sympy
    derivation) for accelerations ``a`` at states ``x`` with joint friction ``k1, k2``."""
    t1, t2, w1, w2 = x.T
    c, s = np.cos(t1 - t2), np.sin(t1 - t2)
    r1 = (p.I1 + p.m1 * p.a1 ** 2 + p.m2 * p.l1 ** 2) * a[:, 2] + p.m2 * p.l1 * p.a2 * c * a[:, 3] \
        - ((p.m1 * p.a1 + p.m2 * p.l1) * p.g * np.sin(t1) - p.m2 * p.l1 * p.a2 * s * w2 ** 2
           - k1 * w1 - k2 * (w1 - w2))
    r2 = p.m2 * p.l1 * p.a2 * c * a[:, 2] + (p.I2 + p.m2 * p.a2 ** 2) * a[:, 3] \
        - (p.m2 * p.a2 * p.g * np.sin(t2) + p.m2 * p.l1 * p.a2 * s * w1 ** 2 + k2 * (w1 - w2))
    return r1, r2


def test_rhs_matches_the_rigs_hand_written_equations():
    p = DoublePendulumParameters.from_array(RIG)
    x = np.random.default_rng(0).uniform([-4, -4, -8, -8], [4, 4, 8, 8], size=(50, 4))
    a = DoublePendulum(p).rhs(x)
    for r in rig_residuals(p, x, a, p.k1, p.k2):
        np.testing.assert_allclose(r, 0, atol=1e-12)
    np.testing.assert_allclose(a[:, :2], x[:, 2:])


def test_flawed_model_is_the_rigs_equations_without_friction():
    p = DoublePendulumParameters.from_array(RIG)
    x = np.random.default_rng(1).uniform([-4, -4, -8, -8], [4, 4, 8, 8], size=(50, 4))
    a = DoublePendulum(p).flawed_model()(x, None)
    np.testing.assert_allclose(a[:, :2], x[:, 2:])
    for r in rig_residuals(p, x, a, 0.0, 0.0):
        np.testing.assert_allclose(r, 0, atol=1e-12)


def test_parameters_from_mat_file(tmp_path):
    path = tmp_path / "params.mat"
    savemat(path, {"EstimatedParameters": np.array([RIG])})
    p = DoublePendulumParameters.from_mat(path)
    assert (p.m1, p.l1, p.k2, p.g) == (RIG[0], RIG[4], RIG[8], RIG[9])
    savemat(tmp_path / "other.mat", {"something": np.array([RIG])})
    with pytest.raises(DataError, match="EstimatedParameters"):
        DoublePendulumParameters.from_mat(tmp_path / "other.mat")
    with pytest.raises(ShapeError, match="10 values"):
        DoublePendulumParameters.from_array(RIG[:9])


def test_bad_parameters_and_states():
    with pytest.raises(ParameterError, match="k1"):
        DoublePendulumParameters(k1=-1.0)
    with pytest.raises(ParameterError, match="m2"):
        DoublePendulumParameters(m2=0.0)
    with pytest.raises(ShapeError, match=r"\(m, 4\)"):
        DoublePendulum().energy(np.zeros((3, 3)))


def test_pivot_force_is_the_momentum_change_of_the_centres_of_mass():
    """Independent check: F = d2/dt2 (m1 r1 + m2 r2) + (m1 + m2) g e_y, by finite differences
    of the simulated centres of mass; at rest hanging down it carries the weight."""
    pend = DoublePendulum()
    p = pend.parameters
    hanging = pend.pivot_force(np.array([[np.pi, np.pi, 0.0, 0.0]]))[0]
    np.testing.assert_allclose(hanging, [0.0, (p.m1 + p.m2) * p.g], atol=1e-12)
    t = np.arange(0, 1.5, 1e-3)
    x = pend.simulate(np.array([2.5, 3.9, 0.0, 0.0]), t)
    cx = p.m1 * p.a1 * np.sin(x[:, 0]) + p.m2 * (p.l1 * np.sin(x[:, 0]) + p.a2 * np.sin(x[:, 1]))
    cy = p.m1 * p.a1 * np.cos(x[:, 0]) + p.m2 * (p.l1 * np.cos(x[:, 0]) + p.a2 * np.cos(x[:, 1]))
    fx, fy = (np.gradient(np.gradient(c, t), t) for c in (cx, cy))
    force = pend.pivot_force(x, friction=True)
    scale = np.max(np.abs(force[:, 0]))
    assert np.max(np.abs(force[5:-5, 0] - fx[5:-5])) < 1e-3 * scale
    assert np.max(np.abs(force[5:-5, 1] - fy[5:-5] - (p.m1 + p.m2) * p.g)) < 2e-3 * scale
