"""The one RK4 step against the analytic solution of a linear ODE with a ramp input."""
import numpy as np
import pytest

from discrepancy.runge_kutta import runge_kutta_step

A = np.array([[0.0, 1.0], [-4.0, -0.4]])     # a damped oscillator, omega = 2 rad/s
B = np.array([0.0, 1.0])
X0 = np.array([1.0, -0.5])


def rates(x, u):
    return x @ A.T + np.multiply.outer(u, B)


def exact(t):
    """x(t) of x' = A x + B t from X0: x = e^{At}(X0 + A⁻²B) - A⁻¹B t - A⁻²B."""
    from scipy.linalg import expm

    ai = np.linalg.inv(A)
    c = ai @ ai @ B
    return expm(A * t) @ (X0 + c) - ai @ B * t - c


def step_error(h):
    """One step from t = 0 with the ramp input at the stage times 0, h/2, h."""
    return np.abs(runge_kutta_step(rates, X0, h, 0.0, h / 2, h) - exact(h)).max()


def test_one_step_error_is_fifth_order_in_the_step():
    errors = np.array([step_error(h) for h in (0.2, 0.1, 0.05)])
    orders = np.log2(errors[:-1] / errors[1:])
    np.testing.assert_allclose(orders, 5.0, atol=0.25)


def test_fixed_span_error_is_fourth_order_and_inputs_at_stage_times_matter():
    def integrate(n, staged=True):
        h, x = 2.0 / n, X0
        for i in range(n):
            t = i * h
            stages = (t, t + h / 2, t + h) if staged else (t, t, t)
            x = runge_kutta_step(rates, x, h, *stages)
        return np.abs(x - exact(2.0)).max()

    errors = np.array([integrate(n) for n in (20, 40, 80)])
    np.testing.assert_allclose(np.log2(errors[:-1] / errors[1:]), 4.0, atol=0.2)
    held = integrate(80, staged=False)          # a held input is only first order
    assert held > 100 * errors[-1]


def test_a_batch_of_rows_with_their_own_step_lengths():
    h = np.array([[0.1], [0.05]])
    rows = runge_kutta_step(rates, np.vstack([X0, X0]), h, 0 * h[:, 0], h[:, 0] / 2, h[:, 0])
    for row, hh in zip(rows, h[:, 0], strict=True):
        np.testing.assert_allclose(row, runge_kutta_step(rates, X0, hh, 0.0, hh / 2, hh),
                                   rtol=1e-15, atol=1e-15)


def test_casadi_symbols_give_the_numpy_step():
    ca = pytest.importorskip("casadi")
    x, u, h = ca.SX.sym("x", 2), ca.SX.sym("u"), ca.SX.sym("h")
    f = ca.Function("f", [x, u], [ca.mtimes(ca.DM(A), x) + ca.DM(B) * u])
    step = ca.Function("step", [x, h], [runge_kutta_step(f, x, h, 0.0, h / 2, h)])
    np.testing.assert_allclose(np.array(step(X0, 0.1)).ravel(),
                               runge_kutta_step(rates, X0, 0.1, 0.0, 0.05, 0.1), rtol=1e-14)
    assert np.abs(np.array(step(X0, 0.1)).ravel() - exact(0.1)).max() < 1e-5
