"""Output feedback: a Kalman filter on the model estimates the unmeasured state for a
state-feedback law; checked against the Kalman filter's own theory on a linear plant (the
filter is exact there, so its reported covariance is the true error covariance) and against
the LQR it must equal in the limit of a perfect sensor."""
import casadi as ca
import numpy as np
import pytest
import sympy as sp
from scipy.linalg import solve_discrete_are

from discrepancy.control import OutputFeedback, closed_loop
from discrepancy.errors import ParameterError, ShapeError
from discrepancy.estimation import ExtendedKalmanFilter
from discrepancy.symbolic import symbol

DT = 0.05
A = np.array([[1, DT], [0, 1]])
B = np.array([[DT ** 2 / 2], [DT]])


def double_integrator():
    x, u = ca.SX.sym("x", 2), ca.SX.sym("u", 1)
    return ca.Function("f", [x, u], [ca.vertcat(x[1], u)])


def lqr_law():
    P = solve_discrete_are(A, B, np.diag([1.0, 0.1]), np.array([[0.1]]))
    K = np.linalg.solve(0.1 + B.T @ P @ B, B.T @ P @ A)
    return lambda k, x: -K @ x


def position_filter(noise):
    return ExtendedKalmanFilter([symbol("v"), symbol("u")], outputs=["p"],
                                process_noise=[0.0, 0.0], measurement_noise=[noise],
                                state_names=["p", "v"], input_names=["u"])


def test_the_filter_errors_match_its_own_covariance_on_a_linear_plant():
    """Position measured with noise 0.01, velocity estimated: the model is exact and the
    plant has no process noise, so the normalised estimation errors e/σ of both states are
    standard normal (their mean square 1 within sampling error), the velocity error shrinks
    as the filter learns, and the loop still brings the state to rest."""
    noise, steps = 0.01, 400
    errors = []
    for seed in range(8):
        x0 = np.array([1.0, -0.5])
        law = OutputFeedback(lqr_law(), position_filter(noise), x0=[0.0, 0.0],
                             P0=[1.0, 1.0], dt=DT)
        run = closed_loop(double_integrator(), law, x0 + [0.0, 0.0], dt=DT, steps=steps,
                          noise_std=[noise, 0.0], seed=seed, outputs=[0])
        # the initial belief is N(0, 1) per state; the truth differs from it by (1, -0.5)
        errors.append((law.estimates - run.x[:steps]) / law.stds)
        assert np.max(np.abs(run.final)) < 1e-2
        e = law.estimation_errors(run)
        assert e["rms"].shape == (2,) and e["max"][1] >= e["rms"][1]
    z = np.concatenate([e[20:] for e in errors])          # after the first second
    np.testing.assert_allclose(np.mean(z ** 2, axis=0), [1.0, 1.0], atol=0.35)
    assert np.all(np.abs(np.mean(z, axis=0)) < 0.3)


def test_with_a_nearly_perfect_sensor_output_feedback_is_the_state_feedback():
    """Measuring p and v exactly (a filter trusting them to 1e-6): the estimates are the
    states and the inputs the LQR's."""
    ekf = ExtendedKalmanFilter([symbol("v"), symbol("u")], outputs=["p", "v"],
                               process_noise=[0.0, 0.0], measurement_noise=[1e-6, 1e-6],
                               state_names=["p", "v"], input_names=["u"])
    law = OutputFeedback(lqr_law(), ekf, x0=[0.0, 0.0], P0=[10.0, 10.0], dt=DT)
    run = closed_loop(double_integrator(), law, [1.0, 0.3], dt=DT, steps=50, outputs=[0, 1])
    full = closed_loop(double_integrator(), lqr_law(), [1.0, 0.3], dt=DT, steps=50)
    np.testing.assert_allclose(run.u, full.u, atol=1e-4)
    np.testing.assert_allclose(law.estimates, run.x[:50], atol=1e-5)


def test_the_law_is_restarted_and_misuse_is_named():
    law = OutputFeedback(lqr_law(), position_filter(0.01), x0=[0.0, 0.0], P0=[1.0, 1.0],
                         dt=DT)
    law(0, [0.5])
    with pytest.raises(ShapeError, match="called twice without notify_applied"):
        law(1, [0.5])
    law.reset()
    assert law.estimates.shape == (0,)
    with pytest.raises(ParameterError, match="estimator must have start, update and predict"):
        OutputFeedback(lqr_law(), object(), x0=[0.0], P0=[1.0], dt=DT)
    with pytest.raises(ParameterError, match="dt must be a positive"):
        OutputFeedback(lqr_law(), position_filter(0.01), x0=[0.0, 0.0], P0=1.0, dt=0.0)
    with pytest.raises(ParameterError, match="law must be callable"):
        OutputFeedback(3, position_filter(0.01), x0=[0.0, 0.0], P0=1.0, dt=DT)
    assert sp  # sympy is what the filter's model is written in
