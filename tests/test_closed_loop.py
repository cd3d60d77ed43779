"""Closed loop: the controller sees noisy states, the actuator keeps the limits, the log."""
import casadi as ca
import numpy as np
import pytest

from discrepancy.control import Limits, closed_loop
from discrepancy.errors import ParameterError, ShapeError


def integrator():
    """dx/dt = u (one state, one input): x[k+1] = x[k] + dt u[k] exactly."""
    x, u = ca.SX.sym("x", 1), ca.SX.sym("u", 1)
    return ca.Function("f", [x, u], [u])


def test_measurement_noise_has_the_given_spread_and_the_plant_does_not_see_it():
    x, u = ca.SX.sym("x", 2), ca.SX.sym("u", 1)
    still = ca.Function("f", [x, u], [ca.vertcat(0 * u, 0 * u)])
    seen = []
    run = closed_loop(still, lambda k, xm: seen.append(xm) or np.zeros(1), [1.0, -2.0],
                      dt=0.01, steps=4000, noise_std=[0.1, 0.001], seed=3, samples=2)
    np.testing.assert_array_equal(run.x[-1], [1.0, -2.0])          # the true state
    noise = np.array(seen) - [1.0, -2.0]
    np.testing.assert_allclose(noise.std(axis=0), [0.1, 0.001], rtol=0.05)
    np.testing.assert_array_equal(run.x_measured[:-1], np.array(seen))
    # the log's grid samples are the very measurements the controller got
    np.testing.assert_array_equal(run.x_measured_dense[:, 0], run.x_measured[:-1])
    assert run.x_measured_dense.shape == (4000, 3, 2)


def test_actuator_saturates_an_aggressive_law_and_the_plant_follows():
    lim = Limits(u_bounds=[[-1.0, 1.0]], du_max=[5.0])
    dt = 0.1
    run = closed_loop(integrator(), lambda k, x: np.array([50.0]), [0.0], dt=dt, steps=4,
                      limits=lim)
    np.testing.assert_allclose(run.u[:, 0], [0.5, 1.0, 1.0, 1.0])   # rate, then bound
    np.testing.assert_allclose(run.u_commanded[:, 0], 50.0)
    np.testing.assert_allclose(run.x[:, 0], np.r_[0, np.cumsum(run.u[:, 0]) * dt], atol=1e-10)
    assert lim.check(run)["respected"]


def test_log_is_cut_per_hold_interval_and_can_stop_at_a_time():
    run = closed_loop(integrator(), lambda k, x: np.array([float(k)]), [0.0], dt=0.1,
                      steps=5, samples=4)
    x, t, u = run.measured_trajectories()
    assert len(x) == len(t) == len(u) == 5 and x[0].shape == (5, 1)
    assert all(np.all(ui == k) for k, ui in enumerate(u))
    x, t, u = run.measured_trajectories(until=0.3)
    assert len(x) == 3 and t[-1][-1] == pytest.approx(0.3)
    lim = Limits(x_bounds=[[-1.0, 0.05]])
    # u = k on interval k: x = t - 0.1 on [0.1, 0.2], sampled every 0.025 s; the first sample
    # above 0.05 + 1 mm of slack is 0.075 at t = 0.175
    assert run.first_exit(lim) == pytest.approx(0.175)


def test_bad_arguments_are_named():
    with pytest.raises(ParameterError, match="steps"):
        closed_loop(integrator(), lambda k, x: np.zeros(1), [0.0], dt=0.1, steps=0)
    with pytest.raises(ShapeError, match="noise_std"):
        closed_loop(integrator(), lambda k, x: np.zeros(1), [0.0], dt=0.1, steps=2,
                    noise_std=[-1.0])


def test_output_feedback_sees_only_the_measured_states_in_the_given_order():
    """With outputs=[1, 0] the law gets (x2 + noise, x1 + noise); the log keeps those two
    and NaN for the third state; the control log is what the law saw."""
    x, u = ca.SX.sym("x", 3), ca.SX.sym("u", 1)
    still = ca.Function("f", [x, u], [ca.vertcat(0 * u, 0 * u, 0 * u)])
    seen = []
    run = closed_loop(still, lambda k, y: seen.append(y) or np.zeros(1), [1.0, -2.0, 5.0],
                      dt=0.01, steps=500, noise_std=[0.1, 0.001, 1.0], seed=3, samples=2,
                      outputs=[1, 0])
    seen = np.array(seen)
    assert seen.shape == (500, 2)
    np.testing.assert_allclose(seen.mean(axis=0), [-2.0, 1.0], atol=0.02)
    np.testing.assert_allclose((seen - [-2.0, 1.0]).std(axis=0), [0.001, 0.1], rtol=0.1)
    assert np.all(np.isnan(run.x_measured[:, 2])) and np.all(np.isnan(run.x_measured_dense[..., 2]))
    y, dt, u_log = run.control_log()
    np.testing.assert_array_equal(y[:-1], seen)
    assert dt == pytest.approx(0.01) and u_log.shape == (501, 1)
    with pytest.raises(ParameterError, match="outputs must be distinct indices"):
        closed_loop(still, lambda k, y: np.zeros(1), [0.0, 0.0, 0.0], dt=0.1, steps=2,
                    outputs=[0, 3])
