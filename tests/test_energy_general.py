"""The dissipation model on mechanical systems other than the paper's: a single pendulum and a
three-link pendulum in joint angles, each simulated with known joint friction. Their
equations of motion come from sympy.physics.mechanics (LagrangesMethod), not from this
package; the fits use the defaults only."""
import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp
from sympy.physics import mechanics as me

import discrepancy as dc

G = 9.81


def chain(masses, lengths, frictions, coulomb=None, *, energies=False):
    """A planar chain of point masses on massless rods, joint angles ``q`` (``q_i`` relative
    to link ``i - 1``; the first from hanging down), viscous joint friction ``k_i`` (and
    Coulomb ``F_i sign(dq_i)``, smoothed over 1e-3 rad/s). Returns ``(rhs(x), energy(x))``,
    and with ``energies`` also ``(T, V)`` in the symbols ``a1..an``, ``w1..wn``."""
    n = len(masses)
    q = me.dynamicsymbols(f"q1:{n + 1}")
    dq = me.dynamicsymbols(f"q1:{n + 1}", 1)
    frame = me.ReferenceFrame("N")
    origin = me.Point("O")
    origin.set_vel(frame, 0)
    angle, point, particles, potential = 0, origin, [], 0
    for i in range(n):
        angle = angle + q[i]
        nxt = point.locatenew(f"P{i}", lengths[i] * (sp.sin(angle) * frame.x
                                                     - sp.cos(angle) * frame.y))
        nxt.v2pt_theory(point, frame, frame.orientnew(f"L{i}", "Axis", (angle, frame.z)))
        particles.append(me.Particle(f"m{i}", nxt, masses[i]))
        potential += masses[i] * G * nxt.pos_from(origin).dot(frame.y)
        point = nxt
    kinetic = sum(p.kinetic_energy(frame) for p in particles)
    lagrangian = kinetic - potential
    torques = [-frictions[i] * dq[i] - (coulomb[i] * sp.tanh(dq[i] / 1e-3) if coulomb else 0)
               for i in range(n)]
    method = me.LagrangesMethod(lagrangian, q, frame=frame)
    method.form_lagranges_equations()
    mass, forcing = method.mass_matrix, method.forcing + sp.Matrix(torques)
    qs, vs = sp.symbols(f"a1:{n + 1}"), sp.symbols(f"w1:{n + 1}")
    to_plain = {**dict(zip(dq, vs, strict=True)), **dict(zip(q, qs, strict=True))}
    mass_f = sp.lambdify([qs, vs], mass.subs(to_plain))
    forcing_f = sp.lambdify([qs, vs], forcing.subs(to_plain))
    energy_f = sp.lambdify([qs, vs], (kinetic + potential).subs(to_plain))

    def rhs(_, x):
        acc = np.linalg.solve(np.array(mass_f(x[:n], x[n:]), float),
                              np.array(forcing_f(x[:n], x[n:]), float).ravel())
        return np.r_[x[n:], acc]

    def energy(x):
        return np.array([energy_f(row[:n], row[n:]) for row in x], float)

    if energies:
        return rhs, energy, (kinetic.subs(to_plain), potential.subs(to_plain))
    return rhs, energy


def swing(rhs, x0, seconds, rate=1000):
    t = np.arange(int(seconds * rate) + 1) / rate
    sol = solve_ivp(rhs, (0, t[-1]), x0, t_eval=t, method="DOP853", rtol=1e-11, atol=1e-11)
    assert sol.success
    return t, sol.y.T


def laws(model):
    return {term.name: c for term, c in zip(model.terms_, model.coef_, strict=True)}


def test_single_pendulum_viscous_and_coulomb_friction():
    rhs, energy = chain([0.5], [0.4], [2e-3], coulomb=[4e-3])
    t, x = swing(rhs, [2.6, 0.0], 20)
    model = dc.DissipationDiscrepancy(energy).fit(x[:, :1], t)
    found = laws(model)
    assert set(found) == {"viscous joint 1", "Coulomb joint 1"}
    assert found["viscous joint 1"] == pytest.approx(2e-3, rel=0.02)
    assert found["Coulomb joint 1"] == pytest.approx(4e-3, rel=0.02)


def test_three_link_pendulum_in_joint_angles():
    k = [3e-3, 1.5e-3, 8e-4]
    rhs, energy = chain([0.3, 0.2, 0.1], [0.3, 0.25, 0.2], k)
    t, x = swing(rhs, [1.2, -0.8, 1.5, 0, 0, 0], 12)
    model = dc.DissipationDiscrepancy(energy).fit(x[:, :3], t)
    found = laws(model)
    assert set(found) == {"viscous joint 1", "viscous joint 2", "viscous joint 3"}
    for i, value in enumerate(k):
        assert found[f"viscous joint {i + 1}"] == pytest.approx(value, rel=0.02)
    assert model.variable_names_ == ["q1", "q2", "q3", "dq1", "dq2", "dq3"]


@pytest.mark.parametrize("n", [1, 3])
def test_lagrangian_system_equals_sympy_mechanics(n):
    """LagrangianSystem derives from T and V alone what LagrangesMethod gives (with the
    friction as a Rayleigh function); its energy and conservative torques agree too."""
    k = [3e-3, 1.5e-3, 8e-4][:n]
    masses, lengths = [0.3, 0.2, 0.1][:n], [0.3, 0.25, 0.2][:n]
    rhs, energy, (kinetic, potential) = chain(masses, lengths, k, energies=True)
    w = sp.symbols(f"w1:{n + 1}")
    system = dc.systems.LagrangianSystem(
        kinetic, potential, [f"a{i + 1}" for i in range(n)], rates=[s.name for s in w],
        dissipation=sum(ki * wi ** 2 for ki, wi in zip(k, w, strict=True)) / 2)
    x = np.random.default_rng(n).uniform(-2, 2, size=(20, 2 * n))
    expected = np.array([rhs(0, row) for row in x])
    np.testing.assert_allclose(system.rhs(x), expected, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(system.energy(x), energy(x), rtol=1e-12, atol=1e-12)
    free = expected.copy()
    free[:, n:] = np.array([rhs(0, np.r_[row[:n], 0 * row[n:]])[n:] for row in x])
    at_rest = np.hstack([x[:, :n], np.zeros((20, n))])
    np.testing.assert_allclose(system.flawed_model()(at_rest)[:, n:], free[:, n:], atol=1e-9)
    if n == 1:  # -dV/dq of a point mass on a rod: -m g l sin(q)
        np.testing.assert_allclose(system.conservative_torques(x)[:, 0],
                                   -masses[0] * G * lengths[0] * np.sin(x[:, 0]), rtol=1e-12)


def test_lagrangian_system_refuses_unknown_symbols():
    a, w, m = sp.symbols("a w m")
    with pytest.raises(dc.errors.ParameterError, match="m"):
        dc.systems.LagrangianSystem(m * w ** 2 / 2, -sp.cos(a), ["a"], rates=["w"])


def test_torque_limit_is_the_largest_gravity_torque_and_binds_the_whole_law():
    """'auto' bounds the torque of the whole law at a joint by the largest gravity torque
    of the swing (m g l max|sin q|); a tighter given limit holds viscous + Coulomb at the
    fastest sample (k max|dq| + F) at the limit."""
    rhs, energy = chain([0.5], [0.4], [2e-3], coulomb=[4e-3])
    t, x = swing(rhs, [2.6, 0.0], 20)
    model = dc.DissipationDiscrepancy(energy).fit(x[:, :1], t)
    edge = 15  # samples the default smoother drops at either end
    largest = 0.5 * G * 0.4 * np.max(np.abs(np.sin(x[edge:-edge, 0])))
    assert model.torque_limit_ == pytest.approx(largest, rel=1e-3)
    assert model.soundness_["sound"] and not model.fit_.active
    tight = dc.DissipationDiscrepancy(energy, torque_limit=8e-3,
                                      friction_terms=model.friction_terms).fit(x[:, :1], t)
    found = laws(tight)
    fastest = np.max(np.abs(x[edge:-edge, 1]))
    whole = found.get("viscous joint 1", 0) * fastest + found.get("Coulomb joint 1", 0)
    assert set(found) <= {"viscous joint 1", "Coulomb joint 1"}
    assert whole == pytest.approx(8e-3, rel=2e-3)
