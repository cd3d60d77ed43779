"""Levenberg–Marquardt with continuity constraints, against answers known independently:
a linear multiple-shooting problem solved by dense normal equations, the same with a bound
against scipy's ``lsq_linear``, and an output-error fit against scipy's ``least_squares``
(single shooting) on identical input."""
import numpy as np
import pytest
import scipy.optimize
import sympy as sp

import discrepancy as dc
from discrepancy.models import gauss_newton, single_shooting
from discrepancy.models.output_fit import _allowed, prepare
from discrepancy.models.output_records import records_of


class LinearSegments:
    """``x_{k+1} = A x_k + b θ``, outputs ``y_k = c·x_k``: segments of ``L`` steps from
    their own states. Linear, so the constrained least squares has one solution."""

    def __init__(self, y, length, A, b, c):
        self.y, self.L, self.A, self.b, self.c = y, length, A, b, c

    def run(self, x, theta, steps):
        xs, dx, dt = [x], [np.eye(2)], [np.zeros(2)]
        for _ in range(steps):
            xs.append(self.A @ xs[-1] + self.b * theta[0])
            dx.append(self.A @ dx[-1])
            dt.append(self.A @ dt[-1] + self.b)
        return np.array(xs), np.array(dx), np.array(dt)

    def evaluate(self, states, theta):
        N = len(states)
        ev = gauss_newton.Evaluation(0.0, np.zeros((N, 2, 2)), np.zeros((N, 2, 1)),
                                     np.zeros((1, 1)), np.zeros((N, 2)), np.zeros(1),
                                     np.zeros((N, 2)), np.zeros((N, 2, 2)), np.zeros((N, 2, 1)))
        for i in range(N):
            last = i == N - 1
            xs, dx, dt = self.run(states[i], theta, self.L)
            rows = slice(0, self.L + (1 if last else 0))
            r = xs[rows] @ self.c - self.y[i * self.L:i * self.L + rows.stop]
            j_s, j_t = dx[rows].transpose(0, 2, 1) @ self.c, dt[rows] @ self.c
            ev.cost += r @ r
            ev.h_ss[i], ev.h_sp[i, :, 0] = j_s.T @ j_s, j_s.T @ j_t
            ev.h_pp += j_t @ j_t
            ev.g_s[i], ev.g_p[0] = j_s.T @ r, ev.g_p[0] + j_t @ r
            ev.ends[i], ev.a[i], ev.b[i, :, 0] = xs[-1], dx[-1], dt[-1]
        return ev


def linear_problem(seed=0):
    rng = np.random.default_rng(seed)
    A = np.array([[0.99, 0.1], [-0.1, 0.98]])
    b, c = np.array([0.0, 0.05]), np.array([1.0, 0.0])
    N, L = 6, 20
    truth = LinearSegments(None, N * L, A, b, c)
    xs, _, _ = truth.run(np.array([1.0, -0.5]), np.array([0.7]), N * L)
    y = xs @ c + 0.01 * rng.standard_normal(N * L + 1)
    problem = LinearSegments(y, L, A, b, c)
    # single shooting is linear in (x0, θ): y ≈ [c·A^k, c·Σ A^j b] (x0, θ)
    _, dx, dt = truth.run(np.zeros(2), np.zeros(1), N * L)
    design = np.c_[dx.transpose(0, 2, 1) @ c, dt @ c]
    return problem, y, design, N


def test_linear_multiple_shooting_equals_the_single_shooting_normal_equations():
    problem, y, design, N = linear_problem()
    exact = np.linalg.lstsq(design, y, rcond=None)[0]
    result = gauss_newton.solve(problem.evaluate, np.zeros((N, 2)), np.zeros(1),
                                np.r_[np.ones(N - 1, bool), False], state_scale=np.ones(2))
    assert result.converged and result.defect < 1e-9
    np.testing.assert_allclose(result.states[0], exact[:2], rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(result.theta, exact[2:], rtol=1e-8)
    assert result.evaluations <= 6                   # linear: Gauss–Newton is exact


def test_a_bound_on_the_first_state_as_scipy_lsq_linear_finds_it():
    problem, y, design, N = linear_problem(1)
    lower, upper = np.full((N, 2), -np.inf), np.full((N, 2), np.inf)
    upper[0, 0] = 0.8                                # the unbounded optimum is near 1.0
    exact = scipy.optimize.lsq_linear(design, y, bounds=([-np.inf, -np.inf, -np.inf],
                                                         [0.8, np.inf, np.inf])).x
    result = gauss_newton.solve(problem.evaluate, np.zeros((N, 2)), np.zeros(1),
                                np.r_[np.ones(N - 1, bool), False], state_scale=np.ones(2),
                                lower=lower, upper=upper)
    assert result.states[0, 0] <= 0.8
    np.testing.assert_allclose(np.r_[result.states[0], result.theta], exact, atol=1e-6)


def test_an_output_error_fit_equals_scipy_least_squares_on_identical_input():
    """The hidden-velocity oscillator with its two discrepancy terms as the support:
    multiple shooting (segments of 40 samples) and single shooting by scipy agree."""
    from scipy.integrate import solve_ivp

    t = np.arange(801) * 0.05
    u = 2 * np.sin(0.9 * t) + np.sin(2.3 * t)
    x = solve_ivp(lambda s, z: [z[1], -z[0] - 0.2 * z[1] - 0.5 * z[0] ** 3
                                + np.interp(s, t, u)], (0, t[-1]), [0.5, -0.3], t_eval=t,
                  rtol=1e-10, atol=1e-10, max_step=0.05).y.T
    y = x[:, 0] + 0.01 * np.random.default_rng(3).standard_normal(len(t))
    pos, vel, u_ = sp.symbols("pos vel u", real=True)
    model = dc.DiscrepancyModel(prior=[vel, -pos - 0.1 * vel + u_], state_names=["pos", "vel"],
                                input_names=["u"], feature_library=dc.CustomLibrary([vel,
                                                                                     pos ** 3]))
    records, _ = records_of(y, t, u, 4, "linear")
    setup = model.make_setup(2, 1)
    fit, _, rows = prepare(setup, records, outputs=["pos"], x0=None, x0_bounds=None,
                           substeps=4, allowed=_allowed(setup), structure=_allowed(setup),
                           options={"segment_length": 40}, passes=10)
    x0s = np.array([[y[0], 0.0]])
    fit.set_coef_scale(x0s)
    support = np.array([[False, False], [True, True]])
    start = np.zeros((2, 2))
    ours = fit.solve(support, start, x0s, rows, 0.0)
    coef, peer_x0s, peer_cost = single_shooting.solve(fit, support, start, x0s, rows, 0.0)
    assert ours.converged
    np.testing.assert_allclose(ours.coef, coef, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(ours.x0s, peer_x0s, rtol=1e-6, atol=1e-8)
    assert ours.cost == pytest.approx(peer_cost, rel=1e-8)
    np.testing.assert_allclose(ours.coef[1], [-0.1, -0.5], rtol=0.02)   # and the truth
