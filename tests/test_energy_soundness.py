"""Soundness of friction laws: holding torques against Newton's laws by hand, turning points
of known signals, and the constraints of the fit against simulated friction."""
import numpy as np
import pytest
import sympy as sp

import discrepancy as dc
from discrepancy.energy import holding_torques, turning_points
from discrepancy.energy.soundness import STATIC_MARGIN, joint_axes

G = 9.81
M1, M2, L1, L2 = 0.7, 0.4, 0.5, 0.3


def two_masses():
    """Point masses on massless rods, relative angles (q1 from hanging down), T and V by hand."""
    q1, q2, w1, w2 = sp.symbols("q1 q2 dq1 dq2")
    x1, y1 = L1 * sp.sin(q1), -L1 * sp.cos(q1)
    x2, y2 = x1 + L2 * sp.sin(q1 + q2), y1 - L2 * sp.cos(q1 + q2)
    speed2 = sum((sp.diff(c, q1) * w1 + sp.diff(c, q2) * w2) ** 2 for c in (x2, y2))
    kinetic = M1 * L1 ** 2 * w1 ** 2 / 2 + M2 * speed2 / 2
    return dc.systems.LagrangianSystem(kinetic, M1 * G * y1 + M2 * G * y2, ["q1", "q2"])


def cross(r, f):
    return r[0] * f[1] - r[1] * f[0]


def test_holding_torque_of_a_single_pendulum_is_its_gravity_torque():
    q, w = sp.symbols("q dq")
    rod = dc.systems.LagrangianSystem(0.5 * 0.4 ** 2 / 6 * w ** 2,
                                      -0.5 * G * 0.2 * sp.cos(q), ["q"])
    angles = np.linspace(-2.5, 2.5, 11)
    x = np.column_stack([angles, np.zeros_like(angles)])
    np.testing.assert_allclose(holding_torques(rod.energy, x, [1.0]),
                               0.5 * G * 0.2 * np.abs(np.sin(angles)), rtol=1e-6, atol=1e-9)


def test_holding_the_shoulder_while_the_elbow_swings_matches_newton():
    """Joint 1 locked (link 1 at rest), link 2 swinging at w2: the base torque balances
    m1's weight and the force rod 2 pulls with, m2 (a2 - g), both at the elbow."""
    rng = np.random.default_rng(0)
    q = rng.uniform(-2, 2, (6, 2))
    w2 = rng.uniform(-4, 4, 6)
    x = np.column_stack([q, np.zeros(6), w2])
    expected = []
    for (q1, q2), spin in zip(q, w2, strict=True):
        r1 = L1 * np.array([np.sin(q1), -np.cos(q1)])
        theta = q1 + q2
        radial, tangent = np.array([np.sin(theta), -np.cos(theta)]), np.array(
            [np.cos(theta), np.sin(theta)])
        accel = -L2 * spin ** 2 * radial + L2 * (-G / L2 * np.sin(theta)) * tangent
        pull = M2 * (accel - np.array([0.0, -G]))
        expected.append(abs(cross(r1, np.array([0.0, -M1 * G]) - pull)))
    got = holding_torques(two_masses().energy, x, [1.0, 0.0])
    np.testing.assert_allclose(got, expected, rtol=1e-5)


def test_holding_the_elbow_while_the_body_turns_matches_newton():
    """Joint 2 locked: the two masses turn as one rigid body about the base; the elbow holds
    m2 on its circle about the elbow, torque (r2 - r1) x m2 (a2 - g)."""
    rng = np.random.default_rng(1)
    q = rng.uniform(-2, 2, (6, 2))
    w1 = rng.uniform(-4, 4, 6)
    x = np.column_stack([q, w1, np.zeros(6)])
    expected = []
    for (q1, q2), spin in zip(q, w1, strict=True):
        r1 = L1 * np.array([np.sin(q1), -np.cos(q1)])
        r2 = r1 + L2 * np.array([np.sin(q1 + q2), -np.cos(q1 + q2)])
        inertia = M1 * L1 ** 2 + M2 * r2 @ r2
        alpha = -G * (M1 * r1[0] + M2 * r2[0]) / inertia
        perp = np.array([-r2[1], r2[0]])
        accel = -spin ** 2 * r2 + alpha * perp
        expected.append(abs(cross(r2 - r1, M2 * (accel - np.array([0.0, -G])))))
    got = holding_torques(two_masses().energy, x, [0.0, 1.0])
    np.testing.assert_allclose(got, expected, rtol=1e-5)


def test_turning_points_of_a_decaying_oscillation_and_none_at_rest():
    t = np.arange(0, 10, 1e-3)
    speed = np.exp(-0.2 * t) * np.cos(2 * np.pi * t)     # reverses at t = 0.25 + k / 2
    found = t[turning_points(speed)]
    np.testing.assert_allclose(found, 0.25 + 0.5 * np.arange(20), atol=1.5e-3)
    noise = 1e-4 * np.random.default_rng(0).standard_normal(5000)
    resting = np.r_[speed, noise]             # comes to rest: noise is no turning point
    assert len(turning_points(resting)) == 20


def test_joint_axes_group_the_terms_at_one_joint_speed():
    pend = dc.systems.DoublePendulum()
    model = dc.DissipationDiscrepancy.from_system(pend)
    axes = {a.label: a for a in joint_axes(model.friction_terms, ["dphi1", "dphi2"])}
    names = {label: sorted(model.friction_terms[i].name.split(" ")[0] for i in axis.terms)
             for label, axis in axes.items()}
    stribeck = ["Stribeck"] * 3                                           # at 3 speeds
    assert names["joint 1"] == ["Coulomb", *stribeck, "air", "viscous"]  # drag on dphi1
    assert names["joint 2"] == ["Coulomb", *stribeck, "viscous"]
    np.testing.assert_allclose(np.abs(axes["joint 2"].direction), [1.0, 1.0])


@pytest.fixture(scope="module")
def swing():
    """A rod pendulum with viscous and Coulomb friction, 20 s, exact states."""
    q, w = sp.symbols("q dq")
    m, length, k, f = 0.5, 0.4, 2e-3, 4e-3
    system = dc.systems.LagrangianSystem(
        m * length ** 2 / 6 * w ** 2, -m * G * length / 2 * sp.cos(q), ["q"],
        dissipation=k * w ** 2 / 2 + f * sp.sqrt(w ** 2 + 1e-6))
    t = np.arange(20001) / 1000
    x = system.simulate([2.6, 0.0], t, rtol=1e-11, atol=1e-11)
    return system, x, t, m * G * length / 2


def test_whole_law_bound_holds_the_sum_of_the_terms(swing):
    """With a bound below the true friction the law's whole torque, viscous plus Coulomb at
    the fastest sample, sits at the bound (each term alone below it would not suffice)."""
    system, x, t, _ = swing
    limit = 0.012
    model = dc.DissipationDiscrepancy(system.energy, torque_limit=limit).fit(
        x[:, :1], t, dq=x[:, 1:])
    laws = dict(zip([term.name for term in model.terms_], model.coef_, strict=True))
    fastest = np.max(np.abs(x[:, 1]))
    whole = laws.get("viscous joint 1", 0) * fastest + laws.get("Coulomb joint 1", 0) \
        + laws.get("air drag dq1", 0) * fastest ** 2 + sum(
            c for name, c in laws.items() if name.startswith("Stribeck"))
    assert whole == pytest.approx(limit, rel=1e-3)
    assert "whole law <= 0.012 N m (joint 1)" in model.fit_.active
    free = dc.DissipationDiscrepancy(system.energy, torque_limit=None).fit(
        x[:, :1], t, dq=x[:, 1:])
    assert free.coef_ @ [fastest, 1.0] > limit        # the bound changed the law


def test_static_friction_stays_below_the_gravity_torque_at_every_turning_point(swing):
    """A swing without friction whose energy falls as if by a Stribeck break-away twice the
    gravity torque at the turning points (no pendulum swinging on would lose it): the fit
    keeps the static torque below m g l |sin q| at every turning point of the recording,
    found from the true states."""
    system, _, t, gravity = swing
    frictionless = dc.systems.LagrangianSystem(system.kinetic, system.potential, ["q"])
    x = frictionless.simulate([2.0, 0.0], t[:8001], rtol=1e-11, atol=1e-11)
    t = t[:8001]
    speed = x[:, 1]
    turns = np.flatnonzero(np.sign(speed[1:]) != np.sign(speed[:-1]))
    lowest = gravity * np.min(np.abs(np.sin(x[turns, 0])))
    stribeck = np.abs(speed) * np.exp(-(speed / 0.1) ** 2)
    excess = 2 * lowest * np.concatenate([[0.0], np.cumsum((stribeck[1:] + stribeck[:-1])
                                                           / 2 * np.diff(t))])
    model = dc.DissipationDiscrepancy(system.energy, max_terms=2)
    record = model.prepare(x, t)
    record.delta_h = record.delta_h + excess
    model.fit_prepared(record, len(t))
    laws = dict(zip([term.name for term in model.terms_], model.coef_, strict=True))
    static = sum(c for name, c in laws.items() if name.startswith(("Coulomb", "Stribeck")))
    assert static > 0.5 * lowest               # the fit wants the loss ...
    assert static <= STATIC_MARGIN * lowest * (1 + 1e-3)   # ... but never sticks the pendulum
    assert any("turning points" in kind for kind in model.fit_.active)
    assert model.soundness_["sound"]
    unsound = dc.DissipationDiscrepancy(system.energy, max_terms=2, turning_points=False,
                                        torque_limit=None).fit_prepared(record, len(t))
    assert not unsound.soundness_["sound"]


def test_an_energy_not_quadratic_in_the_rates_has_no_turning_point_constraint():
    """H = q^2/2 + dq^4/4 is no mechanical energy: no holding torque, so no constraint at
    its turning points (the whole-law bound still applies)."""
    t = np.arange(4000) * 0.005
    q, dq = np.cos(t)[:, None], -np.sin(t)[:, None]
    quartic = lambda x: x[:, 0] ** 2 / 2 + x[:, 1] ** 4 / 4          # noqa: E731
    model = dc.DissipationDiscrepancy(quartic)
    record = model.prepare(np.hstack([q, dq]), t)
    assert len(turning_points(dq[:, 0])) > 5
    assert all(len(record.turns(len(t), a)[0]) == 0 for a in range(len(record.axes)))
    assert not any("turning" in kind for kind in record.limits(len(t)).kinds)
    assert any("whole law" in kind for kind in record.limits(len(t)).kinds)
