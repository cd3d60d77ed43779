"""Planner, replay, TVLQR and sensitivities against analytic results and independent solvers."""
import casadi as ca
import numpy as np
import pytest
from scipy.linalg import expm, solve_discrete_are

import discrepancy as dc
from discrepancy.control import (
    Plan,
    as_casadi,
    from_equations,
    plan_trajectory,
    replay,
    rk4_step,
    swing_up_errors,
    tvlqr,
)
from discrepancy.control.replay import interval_defects
from discrepancy.control.sensitivity import parameter_sensitivity, state_transition
from discrepancy.errors import ExportError, InfeasibleError, ParameterError, ShapeError
from discrepancy.symbolic import symbol
from discrepancy.systems.double_pendulum_on_cart import DoublePendulumOnCart


def double_integrator():
    x, u = ca.SX.sym("x", 2), ca.SX.sym("u", 1)
    return ca.Function("f", [x, u], [ca.vertcat(x[1], u)])


def decay():
    """dx/dt = -x + 0 u (scalar)."""
    x, u = ca.SX.sym("x", 1), ca.SX.sym("u", 1)
    return ca.Function("f", [x, u], [-x + 0 * u])


def test_export_of_sympy_equations_matches_numpy_rhs():
    system = DoublePendulumOnCart()
    f = as_casadi(system.equations())
    rng = np.random.default_rng(0)
    x, u = rng.normal(size=(20, 6)), rng.normal(size=(20, 1))
    values = np.array(f.map(20)(x.T, u.T)).T
    np.testing.assert_allclose(values, system.rhs(x, u), rtol=1e-12, atol=1e-12)


def test_rk4_step_matches_matrix_exponential_on_a_linear_system():
    A = np.array([[0.0, 1.0], [-4.0, -0.3]])
    B = np.array([[0.0], [1.0]])
    x, u = ca.SX.sym("x", 2), ca.SX.sym("u", 1)
    f = ca.Function("f", [x, u], [ca.mtimes(A, x) + ca.mtimes(B, u)])
    dt = 0.05
    M = expm(np.block([[A, B], [np.zeros((1, 3))]]) * dt)  # exact zero-order-hold map
    x0, u0 = np.array([0.3, -1.0]), np.array([2.0])
    exact = M[:2, :2] @ x0 + M[:2, 2:] @ u0
    np.testing.assert_allclose(np.array(rk4_step(f, dt, 5)(x0, u0)).ravel(), exact, atol=1e-9)


def test_minimum_effort_double_integrator_matches_the_analytic_optimum():
    """Rest to rest over distance 1 in 1 s. Continuous optimum u*(t) = 6 - 12 t, ∫u² = 12;
    with N held inputs the optimum is the same line at the interval midpoints scaled by
    N²/(N² - 1) (the least-norm solution of the two linear end conditions)."""
    N = 100
    plan = plan_trajectory(double_integrator(), x0=[0, 0], xf=[1, 0], T=1.0, n_intervals=N,
                           cost="effort", Q=[1, 1], verbose=False)
    mid = plan.t[:-1] + plan.dt / 2
    scale = N ** 2 / (N ** 2 - 1)
    np.testing.assert_allclose(plan.u[:, 0], scale * (6 - 12 * mid), atol=1e-8)
    assert plan.objective == pytest.approx(12.0 * scale, rel=1e-8)
    run = replay(double_integrator(), [0, 0], plan.t, plan.u)
    np.testing.assert_allclose(run.final, [1, 0], atol=1e-9)


def test_infeasible_request_reports_ipopt_status():
    with pytest.raises(InfeasibleError, match="Infeasible_Problem_Detected"):
        plan_trajectory(double_integrator(), x0=[0, 0], xf=[1, 0], T=1.0, n_intervals=20,
                        cost="effort", Q=[1, 1], u_bounds=[[-1, 1]], verbose=False)


def test_bad_requests_are_rejected():
    f = double_integrator()
    with pytest.raises(ParameterError, match="cost"):
        plan_trajectory(f, x0=[0, 0], xf=[1, 0], cost="fast", Q=[1, 1])
    with pytest.raises(ShapeError, match="x0"):
        plan_trajectory(f, x0=[0, 0, 0], xf=[1, 0], Q=[1, 1])
    with pytest.raises(ShapeError, match="u_bounds"):
        plan_trajectory(f, x0=[0, 0], xf=[1, 0], Q=[1, 1], u_bounds=[[1, -1]])
    with pytest.raises(ParameterError, match="model must be"):
        plan_trajectory("pendulum", x0=[0, 0], xf=[1, 0])
    with pytest.raises(ShapeError, match="law must have"):
        replay(f, [0, 0], np.linspace(0, 1, 11), np.zeros((5, 1)))


def test_numpy_only_term_cannot_be_exported_and_the_error_names_it():
    rng = np.random.default_rng(1)
    x = rng.normal(size=(200, 2))
    u = rng.normal(size=(200, 1))
    x_dot = np.column_stack([x[:, 1], np.abs(x[:, 0]) + u[:, 0]])
    x2, uu = symbol("x2"), symbol("u")
    model = dc.DiscrepancyModel(prior=[x2, uu], optimizer=dc.STLSQ(threshold=0.1),
                                feature_library=dc.CustomLibrary(functions={"abs": np.abs}))
    model.fit(x, t=0.01, u=u, x_dot=x_dot)
    with pytest.raises(ExportError, match="abs"):
        plan_trajectory(model, x0=[0, 0], xf=[1, 0], Q=[1, 1], verbose=False)


def test_sampled_feedback_is_held_between_grid_times():
    """dx/dt = u with u = -k x(t_k) held: x[k+1] = (1 - k dt) x[k] exactly."""
    x, u = ca.SX.sym("x", 1), ca.SX.sym("u", 1)
    f = ca.Function("f", [x, u], [u])
    t = np.linspace(0, 1, 11)
    run = replay(f, [1.0], t, lambda k, xk: -2.0 * xk, samples=3)
    np.testing.assert_allclose(run.x[:, 0], 0.8 ** np.arange(11), rtol=1e-10)
    assert run.x_dense.shape == (10, 4, 1)


def test_tvlqr_gain_approaches_the_stationary_riccati_solution():
    f = double_integrator()
    plan = plan_trajectory(f, x0=[0, 0], xf=[0, 0], T=20.0, n_intervals=200, cost="effort",
                           Q=[1, 1], verbose=False)
    tracker = tvlqr(f, plan, Q=[1.0, 2.0], R=0.5)
    dt = plan.dt
    A = np.array([[1, dt], [0, 1]])
    B = np.array([[dt ** 2 / 2], [dt]])
    P = solve_discrete_are(A, B, np.diag([1.0, 2.0]), np.array([[0.5]]))
    K = np.linalg.solve(0.5 + B.T @ P @ B, B.T @ P @ A)
    np.testing.assert_allclose(tracker.gains[0], K, rtol=1e-6)


def test_sensitivities_of_a_decaying_state_match_the_analytic_values():
    """dx/dt = -x + c: dx(T)/dc = 1 - exp(-T); dx(T)/dx(0) = exp(-T)."""
    f = decay()
    plan = plan_trajectory(f, x0=[1.0], xf=[np.exp(-2.0)], T=2.0, n_intervals=40, cost="effort",
                           Q=[1], verbose=False)
    x, u = ca.SX.sym("x", 1), ca.SX.sym("u", 1)
    one = ca.Function("one", [x, u], [ca.SX(1)])
    assert parameter_sensitivity(f, one, plan)[0] == pytest.approx(1 - np.exp(-2.0), rel=1e-8)
    assert state_transition(f, plan)[0, 0] == pytest.approx(np.exp(-2.0), rel=1e-8)


@pytest.mark.slow
def test_swing_up_plan_is_accurate_on_its_own_model():
    system = DoublePendulumOnCart()
    f = from_equations(*system.equations())
    xb = np.tile([-np.inf, np.inf], (6, 1))
    xb[2] = [-0.5, 0.5]
    x0 = np.array([np.pi, np.pi, 0, 0, 0, 0])
    plan = plan_trajectory(f, x0=x0, xf=np.zeros(6), cost="effort", x_bounds=xb,
                           u_bounds=[[-20, 20]], n_intervals=135, substeps=10, verbose=False)
    assert plan.status == "Solve_Succeeded"
    assert np.all(np.abs(plan.x[:, 2]) <= 0.5 + 1e-8) and np.all(np.abs(plan.u) <= 20 + 1e-8)
    assert interval_defects(f, plan).max() < 1e-6
    own = replay(f, x0, plan.t, plan.u)  # CVODES
    assert np.max(np.abs(own.final - plan.x[-1])) < 0.02
    assert swing_up_errors(own.final, angles=(0, 1), rates=(3, 4))["success"]
    scipy_run = replay(system.rhs, x0, plan.t, plan.u)  # DOP853 on the numpy form
    np.testing.assert_allclose(scipy_run.final, own.final, atol=1e-4)


def test_tvlqr_hands_over_to_the_stationary_lqr_after_the_plan():
    """Double integrator (RK4 exact on quadratics): with Q_final='lqr' the recursion starts at
    the discrete Riccati solution, stays there, and the tracker balances with its gain."""
    f = double_integrator()
    plan = plan_trajectory(f, x0=[1, 0], xf=[0, 0], T=2.0, n_intervals=20, cost="effort",
                           Q=[1, 1], verbose=False)
    tracker = tvlqr(f, plan, Q=[1.0, 2.0], R=0.5, Q_final="lqr")
    dt = plan.dt
    A, B = np.array([[1, dt], [0, 1]]), np.array([[dt ** 2 / 2], [dt]])
    P = solve_discrete_are(A, B, np.diag([1.0, 2.0]), np.array([[0.5]]))
    K = np.linalg.solve(0.5 + B.T @ P @ B, B.T @ P @ A)
    np.testing.assert_allclose(tracker.cost_to_go[-1], P, rtol=1e-10)
    np.testing.assert_allclose(tracker.cost_to_go[0], P, rtol=1e-8)
    np.testing.assert_allclose(tracker.final_gain, K, rtol=1e-10)
    x = np.array([0.1, -0.2])
    np.testing.assert_allclose(tracker(len(plan.u) + 5, x), -K @ x, rtol=1e-10)
    x1, u1 = ca.SX.sym("x", 1), ca.SX.sym("u", 1)
    drift = ca.Function("f", [x1, u1], [x1 + 0 * u1])   # the input cannot stop x' = x
    t = np.linspace(0, 1, 11)
    free = Plan(t=t, x=np.exp(t)[:, None], u=np.zeros((10, 1)), cost="effort", objective=0.0,
                status="given", iterations=0, solve_time=0.0, substeps=4)
    with pytest.raises(InfeasibleError, match="stabilisable"):
        tvlqr(drift, free, Q_final="lqr")
    with pytest.raises(ParameterError, match="Q_final"):
        tvlqr(f, plan, Q_final="riccati")
