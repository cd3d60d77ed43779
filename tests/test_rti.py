"""Real-time iteration MPC: exact on linear systems (the LQR) and converging to IPOPT's optimum
on a nonlinear one (closed loops with limits and a swing-up: tests/test_mpc.py, both solvers)."""
import casadi as ca
import numpy as np
import pytest
from scipy.linalg import solve_discrete_are

from discrepancy.control import MPC, Limits
from discrepancy.errors import ParameterError


def double_integrator():
    x, u = ca.SX.sym("x", 2), ca.SX.sym("u", 1)
    return ca.Function("f", [x, u], [ca.vertcat(x[1], u)])


def pendulum():
    """Damped pendulum driven by a torque: x = (angle, rate)."""
    x, u = ca.SX.sym("x", 2), ca.SX.sym("u", 1)
    return ca.Function("f", [x, u], [ca.vertcat(x[1], -9.81 * ca.sin(x[0]) - 0.1 * x[1] + u)])


@pytest.mark.parametrize("qp_solver", ["daqp", "qpoases", "osqp"])
def test_one_step_on_a_linear_system_is_the_lqr(qp_solver):
    """For linear dynamics the Gauss-Newton QP is the problem itself: one step from any
    guess gives the infinite-horizon LQR's first input with the Riccati terminal weight."""
    dt = 0.1
    A, B = np.array([[1, dt], [0, 1]]), np.array([[dt ** 2 / 2], [dt]])
    Q, R = np.diag([2.0, 0.5]), np.array([[0.3]])
    P = solve_discrete_are(A, B, Q, R)
    K = np.linalg.solve(R + B.T @ P @ B, B.T @ P @ A)
    mpc = MPC(double_integrator(), dt=dt, horizon=8, Q=[2.0, 0.5], R=0.3, solver="rti",
              qp_solver=qp_solver)
    for x0 in ([1.0, 0.0], [-0.3, 2.0]):
        sol = mpc.solve(np.array(x0), np.zeros((9, 2)), np.zeros((8, 1)), P=P)
        assert sol.success and sol.iterations == 1
        np.testing.assert_allclose(sol.u[0], -K @ x0, rtol=1e-5, atol=1e-7)
        np.testing.assert_allclose(sol.x[1], A @ x0 + B @ sol.u[0], atol=1e-9)


def test_repeated_steps_converge_to_the_ipopt_optimum_with_active_limits():
    """A nonlinear pendulum sent from hanging towards upright with |u| <= 4, |du/dt| <= 60 and
    the angle bounded by 2.5 rad (soft): ten Gauss-Newton steps reach IPOPT's converged
    solution (tolerance 1e-10) on the same problem."""
    lim = Limits(x_bounds=[[-np.inf, 2.5], [-np.inf, np.inf]], u_bounds=[[-4.0, 4.0]],
                 du_max=[60.0])
    kw = dict(dt=0.05, horizon=20, Q=[10.0, 1.0], R=0.1, limits=lim, substeps=2)
    x_ref, u_ref = np.tile([np.pi, 0.0], (21, 1)), np.zeros((20, 1))
    x0 = np.array([0.2, 0.0])
    exact = MPC(pendulum(), solver="ipopt", max_iter=500, tol=1e-10, **kw).solve(
        x0, x_ref, u_ref)
    assert exact.success
    assert np.max(np.abs(exact.u)) == pytest.approx(4.0, abs=1e-6)   # the input bound acts
    rti = MPC(pendulum(), solver="rti", max_iter=10, **kw).solve(x0, x_ref, u_ref)
    assert rti.success and rti.iterations == 10
    np.testing.assert_allclose(rti.u, exact.u, atol=1e-5)
    np.testing.assert_allclose(rti.x, exact.x, atol=1e-6)
    assert rti.objective == pytest.approx(exact.objective, rel=1e-5)   # slacks weigh 1e4


def test_bad_solver_settings_are_named():
    f = double_integrator()
    with pytest.raises(ParameterError, match="solver must be one of"):
        MPC(f, dt=0.1, solver="snopt")
    with pytest.raises(ParameterError, match="qp_solver must be a CasADi QP solver"):
        MPC(f, dt=0.1, solver="rti", qp_solver="nonesuch")
    with pytest.raises(ParameterError, match="max_iter must be None or an integer >= 1"):
        MPC(f, dt=0.1, solver="rti", max_iter=0)
    with pytest.raises(ParameterError, match="compile must be True or False"):
        MPC(f, dt=0.1, solver="rti", compile="yes")
