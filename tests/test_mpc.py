"""Nonlinear MPC: the LQR it must equal when unconstrained, the limits it must keep, a
swing-up on a plant simulated by scipy from the system's own numpy equations."""
import casadi as ca
import numpy as np
import pytest
from scipy.linalg import solve_discrete_are

import discrepancy as dc
from discrepancy.control import MPC, Limits, closed_loop, plan_trajectory, swing_up_errors
from discrepancy.errors import ExportError, ParameterError, ShapeError
from discrepancy.symbolic import symbol
from discrepancy.systems import PendulumOnCart


def double_integrator():
    x, u = ca.SX.sym("x", 2), ca.SX.sym("u", 1)
    return ca.Function("f", [x, u], [ca.vertcat(x[1], u)])


def test_unconstrained_mpc_with_the_riccati_terminal_weight_is_the_lqr():
    """Held input on a double integrator: x[k+1] = A x + B u exactly (RK4 is exact on
    quadratics); with terminal weight P from the discrete Riccati equation the MPC's first
    input is the infinite-horizon LQR's -K x."""
    dt = 0.1
    A, B = np.array([[1, dt], [0, 1]]), np.array([[dt ** 2 / 2], [dt]])
    Q, R = np.diag([2.0, 0.5]), np.array([[0.3]])
    P = solve_discrete_are(A, B, Q, R)
    K = np.linalg.solve(R + B.T @ P @ B, B.T @ P @ A)
    mpc = MPC(double_integrator(), dt=dt, horizon=8, Q=[2.0, 0.5], R=0.3, max_iter=100,
              tol=1e-12)
    for x0 in ([1.0, 0.0], [-0.3, 2.0]):
        sol = mpc.solve(np.array(x0), np.zeros((9, 2)), np.zeros((8, 1)), P=P)
        assert sol.success
        np.testing.assert_allclose(sol.u[0], -K @ x0, rtol=1e-6, atol=1e-8)
        # and the predicted states follow the exact discrete dynamics
        np.testing.assert_allclose(sol.x[1], A @ x0 + B @ sol.u[0], atol=1e-9)


SOLVERS = {"ipopt": {"solver": "ipopt", "max_iter": 50}, "rti": {"solver": "rti"}}


@pytest.mark.parametrize("solver", list(SOLVERS))
def test_mpc_keeps_the_limits_when_the_reference_lies_beyond_them(solver):
    """Sent to x = 2 through a wall at x = 1 with |u| <= 1 and |du/dt| <= 5: the closed loop
    stops at the wall (soft bound, checked on the simulated trajectory), inputs kept, with
    IPOPT and with the real-time iteration."""
    lim = Limits(x_bounds=[[-1.0, 1.0], [-np.inf, np.inf]], u_bounds=[[-1.0, 1.0]],
                 du_max=[5.0])
    mpc = MPC(double_integrator(), dt=0.1, horizon=15, Q=[1.0, 0.1], R=0.01, limits=lim,
              **SOLVERS[solver])
    ref_x, ref_u = np.tile([2.0, 0.0], (16, 1)), np.zeros((15, 1))
    last = {}

    def law(k, x):
        last["sol"] = mpc.solve(x, ref_x, ref_u, u_prev=last.get("u"), warm=last.get("sol"))
        last["u"] = last["sol"].u[0]
        return last["u"]

    run = closed_loop(double_integrator(), law, [0.0, 0.0], dt=0.1, steps=60, limits=lim,
                      samples=10)
    report = lim.check(run)
    assert report["respected"], report
    np.testing.assert_allclose(run.u, run.u_commanded, atol=1e-9)   # nothing to clip
    assert run.final[0] == pytest.approx(1.0, abs=0.01)     # pushed against the wall


@pytest.mark.parametrize("solver", [{"max_iter": 5}, {"solver": "rti"}],
                         ids=["ipopt, 5 iterations", "real-time iteration"])
def test_swing_up_of_a_pendulum_on_a_cart_with_noise_on_its_true_dynamics(solver):
    system = PendulumOnCart()
    lim = Limits.named(system.state_names, system.input_names, states={"s": 0.25},
                       inputs={"u": 15}, rates={"u": 500})
    x0, dt = np.array([np.pi, 0, 0, 0]), 0.02
    plan = plan_trajectory(system.equations(), x0=x0, xf=np.zeros(4), T=1.5, n_intervals=75,
                           Q=(10, 20, 1, 0.1), limits=lim, verbose=False)
    tight = Limits.named(system.state_names, system.input_names, states={"s": 0.24},
                         inputs={"u": 15}, rates={"u": 500})   # 1 cm back-off on the rail
    mpc = MPC(system.equations(), dt=dt, horizon=20, Q=(10, 20, 1, 0.1), limits=tight,
              substeps=1, **solver)
    law = mpc.follow(plan)
    run = closed_loop(system.rhs, law, x0, dt=dt, steps=125, limits=lim, samples=4,
                      noise_std=[1e-3, 5e-4, 2e-2, 5e-3], seed=0)   # scipy DOP853 plant
    assert lim.check(run)["respected"]
    assert swing_up_errors(run.final, angles=(0,), rates=(2,))["success"]
    assert len(law.solve_times) == 125 and max(law.iterations) <= 5
    assert solver.get("solver") != "rti" or all(law.converged)
    # after the plan the reference holds the upright state with zero input
    x_ref, u_ref, P = law.window(len(plan.u) + 3)
    np.testing.assert_array_equal(x_ref, np.zeros((21, 4)) + plan.x[-1])
    np.testing.assert_array_equal(u_ref, 0.0)
    np.testing.assert_allclose(P, law.tracker.cost_to_go[-1])


def test_bad_settings_and_a_model_without_symbolic_form_are_named():
    f = double_integrator()
    with pytest.raises(ParameterError, match="horizon must be an integer >= 2"):
        MPC(f, dt=0.1, horizon=1)
    with pytest.raises(ParameterError, match="dt must be a positive"):
        MPC(f, dt=0.0)
    with pytest.raises(ShapeError, match="x_ref must be"):
        MPC(f, dt=0.1, horizon=4).solve(np.zeros(2), np.zeros((4, 2)), np.zeros((4, 1)))
    rng = np.random.default_rng(1)
    x, u = rng.normal(size=(200, 2)), rng.normal(size=(200, 1))
    x_dot = np.column_stack([x[:, 1], np.abs(x[:, 0]) + u[:, 0]])
    model = dc.DiscrepancyModel(prior=[symbol("x2"), symbol("u")],
                                optimizer=dc.STLSQ(threshold=0.1),
                                feature_library=dc.CustomLibrary(functions={"abs": np.abs}))
    model.fit(x, t=0.01, u=u, x_dot=x_dot)
    with pytest.raises(ExportError, match="abs"):
        MPC(model, dt=0.1)


@pytest.mark.parametrize("kw, pattern", [
    ({"Q": [-1, -1]}, r"Q must be positive semidefinite .*diagonal entries \[0, 1\] are negative"),
    ({"Q": [[1, 2], [2, 1]]}, r"Q must be positive semidefinite .*smallest eigenvalue is -1"),
    ({"R": -0.3}, r"R must be positive semidefinite"),
    ({"Q": [[1, 1], [0, 1]]}, r"Q must be a symmetric matrix"),
    ({"soft_penalty": -5.0}, r"soft_penalty must be a finite number > 0; got -5"),
    ({"horizon": 10**9}, r"horizon must be an integer >= 2 and <= 10000"),
    ({"substeps": 0}, r"substeps must be an integer >= 1"),
])
def test_weights_and_sizes_are_checked_by_name(kw, pattern):
    with pytest.raises(ParameterError, match=pattern):
        MPC(double_integrator(), dt=0.1, **kw)


def test_numpy_integers_are_integers():
    """np.int64 horizons and substeps give the same controller as Python ints (the LQR
    check above: same first input), and closed_loop takes np.int64 steps."""
    x0, xr, ur = np.array([1.0, 0.0]), np.zeros((9, 2)), np.zeros((8, 1))
    as_int = MPC(double_integrator(), dt=0.1, horizon=8, substeps=2, tol=1e-12)
    as_numpy = MPC(double_integrator(), dt=0.1, horizon=np.int64(8), substeps=np.int64(2),
                   max_iter=np.int64(100), tol=1e-12)
    np.testing.assert_array_equal(as_numpy.solve(x0, xr, ur).u, as_int.solve(x0, xr, ur).u)
    run = closed_loop(double_integrator(), lambda k, x: np.array([-x[0]]), x0, dt=0.1,
                      steps=np.int64(3))
    assert len(run.t) == 4


def test_stationary_lqr_takes_diagonal_weights_and_refuses_negative_ones():
    """Q as a list of diagonal entries gives scipy's LQR of the exact held-input step (it
    silently returned (None, None) before); a negative weight is refused by name."""
    from discrepancy.control import stationary_lqr

    dt = 0.1
    A, B = np.array([[1, dt], [0, 1]]), np.array([[dt ** 2 / 2], [dt]])
    P = solve_discrete_are(A, B, np.diag([2.0, 0.5]), np.array([[0.3]]))
    K, P_lqr = stationary_lqr(double_integrator(), [0, 0], [0], dt=dt, substeps=np.int64(2),
                              Q=[2.0, 0.5], R=0.3)
    np.testing.assert_allclose(P_lqr, P, rtol=1e-9)
    np.testing.assert_allclose(K, np.linalg.solve(0.3 + B.T @ P @ B, B.T @ P @ A), rtol=1e-9)
    with pytest.raises(ParameterError, match="Q must be positive semidefinite"):
        stationary_lqr(double_integrator(), [0, 0], [0], dt=dt, substeps=2, Q=[-1, 1], R=1)
