"""The discretised hybrid model of output-error fits: its sensitivities against central
finite differences of its own simulation, its segments against one run through the
record, compiled code against CasADi's virtual machine, and the RK4 steps against
``simulate(method="rk4")``."""
import numpy as np
import pytest
import sympy as sp

import discrepancy as dc
from discrepancy.models.inputs import stage_inputs
from discrepancy.models.shooting import ShootingModel

pytest.importorskip("casadi")

POS, VEL, U = sp.symbols("pos vel u", real=True)
H1, H2 = sp.symbols("h1 h2", real=True)


def oscillator_setup():
    model = dc.DiscrepancyModel(prior=[VEL, -POS - 0.1 * VEL + U], state_names=["pos", "vel"],
                                input_names=["u"],
                                feature_library=dc.PolynomialLibrary(3, variables=["pos", "vel"]))
    return model.make_setup(2, 1)


def tanks_setup():
    """Torricelli tanks: the upper level goes below 0 under a negative inflow, where
    ``sqrt(max(h1, 0))`` is flat (the chain rule's ``inf * 0`` must not leak in)."""
    root1, root2 = sp.sqrt(sp.Max(H1, 0)), sp.sqrt(sp.Max(H2, 0))
    model = dc.DiscrepancyModel(prior=[-0.5 * root1 + 0.4 * U, 0.5 * root1 - 0.6 * root2],
                                state_names=["h1", "h2"], input_names=["u"],
                                feature_library=dc.CustomLibrary([sp.Integer(1), H1, H2, U]))
    return model.make_setup(2, 1)


def record(m=300, dt=0.05, shift=0.0):
    t = np.arange(m) * dt
    u = np.sin(0.7 * t) + 0.5 * np.sin(2.1 * t + 1) + shift
    return t, u, np.diff(t), stage_inputs(u, t, 1, 2)


def finite_differences(shooting, x0, stages, h, coef, index, eps=1e-6):
    """``d states / d x0`` ``(m, n, n)`` and ``/ d coef[index]`` ``(m, n, q)``, central."""
    def run(x, c):
        return shooting.simulate(x, stages, h, c)
    d_x0 = np.stack([(run(x0 + eps * e, coef) - run(x0 - eps * e, coef)) / (2 * eps)
                     for e in np.eye(len(x0))], axis=-1)
    d_coef = []
    for i in index:
        step = np.zeros(coef.size)
        step[i] = eps
        step = step.reshape(coef.shape)
        d_coef.append((run(x0, coef + step) - run(x0, coef - step)) / (2 * eps))
    return d_x0, np.stack(d_coef, axis=-1)


@pytest.mark.parametrize("jit", [False, True])
def test_sensitivities_equal_finite_differences(jit):
    setup = oscillator_setup()
    shooting = ShootingModel(setup, 2, jit=jit)
    _, _, h, stages = record()
    coef = np.zeros((2, setup.n_features))
    coef[1, [2, 6]] = [-0.1, -0.5]                           # vel, pos^3
    index = [setup.n_features + j for j in (2, 6, 9)]        # vel, pos^3, vel^3 of vel'
    x0 = np.array([0.5, -0.3])
    sens = shooting.sensitivities(x0, stages, h, coef, index)
    d_x0, d_coef = finite_differences(shooting, x0, stages, h, coef, index)
    scale = np.abs(d_coef).max()
    np.testing.assert_allclose(sens.d_x0, d_x0, atol=1e-7 * np.abs(d_x0).max())
    np.testing.assert_allclose(sens.d_coef, d_coef, atol=1e-7 * scale)
    np.testing.assert_allclose(sens.states, shooting.simulate(x0, stages, h, coef), rtol=1e-13,
                               atol=1e-13)


def test_sensitivities_below_a_clamped_square_root_equal_finite_differences():
    """sqrt(max(h1, 0)) with h1 < 0 for a while: the derivative there is the coefficient's
    alone; differentiating the RK4 step as a whole gave NaN and lost it."""
    setup = tanks_setup()
    shooting = ShootingModel(setup, 2, jit=False)
    _, u, h, stages = record(400, 0.2, shift=-0.4)
    coef = np.zeros((2, 4))
    coef[0, 1] = -0.05
    x0 = np.array([0.3, 0.4])
    sens = shooting.sensitivities(x0, stages, h, coef, [1, 3])
    assert sens.states[:, 0].min() < -0.1 and np.all(np.isfinite(sens.d_coef))
    d_x0, d_coef = finite_differences(shooting, x0, stages, h, coef, [1, 3], eps=1e-7)
    negative = sens.states[:, 0] < -1e-3                      # away from the kink itself
    np.testing.assert_allclose(sens.d_coef[negative], d_coef[negative],
                               atol=1e-6 * np.abs(d_coef).max())
    np.testing.assert_allclose(sens.d_x0[negative], d_x0[negative],
                               atol=1e-6 * np.abs(d_x0).max())


def test_segments_from_the_trajectory_reproduce_it_and_its_sensitivities():
    setup = oscillator_setup()
    shooting = ShootingModel(setup, 2, jit=False)
    _, _, h, stages = record(301)
    coef = np.zeros((2, setup.n_features))
    coef[1, 6] = -0.5
    index = [setup.n_features + 6]
    x0 = np.array([0.2, 0.1])
    whole = shooting.sensitivities(x0, stages, h, coef, index)
    length = 60
    cols, lengths = shooting.columns(stages, h, length)
    starts = whole.states[::length][:5]
    seg = shooting.segments(starts, cols, lengths, coef, index)
    np.testing.assert_allclose(seg.states.reshape(-1, 2)[[i * (length + 1) + j for i in range(5)
                                                          for j in range(length)]],
                               whole.states[:300], rtol=1e-12, atol=1e-12)
    # the chain rule across segments: d x(120) / d x0 = A_2 A_1 = seg 1's end times seg 0's
    chained = seg.d_x0[1, -1] @ seg.d_x0[0, -1]
    np.testing.assert_allclose(chained, whole.d_x0[2 * length], rtol=1e-10, atol=1e-12)
    threaded = ShootingModel(setup, 2, jit=False, n_jobs=2).segments(starts, cols, lengths,
                                                                     coef, index)
    np.testing.assert_array_equal(threaded.states, seg.states)


def test_steps_are_the_steps_simulate_takes():
    setup = oscillator_setup()
    model = dc.DiscrepancyModel(prior=[VEL, -POS - 0.1 * VEL + U], state_names=["pos", "vel"],
                                input_names=["u"],
                                feature_library=dc.PolynomialLibrary(3, variables=["pos", "vel"]))
    t, u, h, stages = record()
    coef = np.zeros((2, setup.n_features))
    coef[1, 6] = -0.5
    x = np.c_[np.sin(t), np.cos(t)]
    model.fit(x, t=t, u=u, x_dot=np.zeros_like(x))            # any fit: its set-up and names
    model = model.with_coefficients(coef)
    expected = model.simulate([0.5, -0.3], t, u=u, method="rk4", substeps=2, compiled=False)
    ours = ShootingModel(setup, 2, jit=True).simulate([0.5, -0.3], stages, h, coef)
    np.testing.assert_allclose(ours, expected, rtol=1e-12, atol=1e-12)
