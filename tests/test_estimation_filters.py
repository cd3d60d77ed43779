"""Kalman filters and the RTS smoother against independent truth: the textbook Kalman filter
and smoother written out with numpy on the exact discretisation of a linear system (matrix
exponential, Van Loan's noise integral), the UKF against the EKF on linear dynamics, and the
normalised innovations of a nonlinear system against their chi-squared law."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg
import sympy as sp

import discrepancy as dc
from discrepancy.estimation import ExtendedKalmanFilter, FilterResult, UnscentedKalmanFilter
from discrepancy.symbolic import symbol

BACKENDS = ["casadi", "numpy"]
A = np.array([[0.0, 1.0], [-2.0, -0.3]])
B = np.array([[0.0], [1.0]])
Q_STD, R_STD, DT = np.array([0.0, 0.3]), np.array([0.05]), 0.05


def linear(x, u):
    return x @ A.T + u @ B.T


def exact_discretisation(dt):
    """``Φ = e^{A dt}``, the zero-order-hold input matrix and Van Loan's ``∫ Φ Q Φᵀ``."""
    n = len(A)
    M = np.zeros((2 * n, 2 * n))
    M[:n, :n], M[:n, n:], M[n:, n:] = -A, np.diag(Q_STD ** 2), A.T
    E = scipy.linalg.expm(M * dt)
    phi = E[n:, n:].T
    return phi, np.linalg.solve(A, phi - np.eye(n)) @ B, phi @ E[:n, n:]


def linear_record(m=300, seed=0):
    rng = np.random.default_rng(seed)
    phi, bd, qd = exact_discretisation(DT)
    u = np.sin(0.7 * DT * np.arange(m))[:, None]
    x, ys = np.array([1.0, 0.0]), []
    for k in range(m):
        ys.append(x[0] + R_STD[0] * rng.standard_normal())
        x = phi @ x + bd @ u[k] + rng.multivariate_normal(np.zeros(2), qd)
    return np.array(ys)[:, None], u


def textbook_filter(y, u, x0, P0, skip=()):
    """The Kalman filter as in any textbook, on the exact discretisation; updates at the
    samples in ``skip`` are left out (missing measurements)."""
    phi, bd, qd = exact_discretisation(DT)
    H, R = np.array([[1.0, 0.0]]), np.diag(R_STD ** 2)
    x, P = x0.copy(), P0.copy()
    out = {"x": [], "P": [], "xp": [], "Pp": [], "ll": 0.0}
    for k in range(len(y)):
        out["xp"].append(x)
        out["Pp"].append(P)
        if k not in skip:
            S = H @ P @ H.T + R
            K = P @ H.T @ np.linalg.inv(S)
            e = y[k] - H @ x
            out["ll"] -= 0.5 * (e @ np.linalg.solve(S, e) + np.log(np.linalg.det(S))
                                + np.log(2 * np.pi))
            x, P = x + K @ e, (np.eye(2) - K @ H) @ P
        out["x"].append(x)
        out["P"].append(P)
        x, P = phi @ x + bd @ u[k], phi @ P @ phi.T + qd
    return {key: np.array(v) for key, v in out.items()}


def textbook_smoother(run):
    """Rauch–Tung–Striebel as in the textbook, from the textbook filter's output."""
    phi = exact_discretisation(DT)[0]
    xs, Ps = run["x"].copy(), run["P"].copy()
    for k in range(len(xs) - 2, -1, -1):
        G = run["P"][k] @ phi.T @ np.linalg.inv(run["Pp"][k + 1])
        xs[k] = run["x"][k] + G @ (xs[k + 1] - run["xp"][k + 1])
        Ps[k] = run["P"][k] + G @ (Ps[k + 1] - run["Pp"][k + 1]) @ G.T
    return xs, Ps


def make(cls=ExtendedKalmanFilter, backend="casadi", **kw):
    return cls(linear, outputs=["x1"], process_noise=Q_STD, measurement_noise=R_STD,
               state_names=["x1", "x2"], input_names=["u"], u_hold="zoh", backend=backend,
               **kw)


X0, P0 = np.array([0.5, 0.0]), np.eye(2)


@pytest.mark.parametrize("backend", BACKENDS)
def test_ekf_equals_the_textbook_kalman_filter_on_a_linear_system(backend):
    y, u = linear_record()
    truth = textbook_filter(y, u, X0, P0)
    run = make(backend=backend).filter(y, DT, u=u, x0=X0, P0=P0)
    assert isinstance(run, FilterResult)
    assert np.allclose(run.x, truth["x"], atol=1e-7)
    assert np.allclose(run.P, truth["P"], atol=1e-8)
    assert np.allclose(run.x_predicted, truth["xp"], atol=1e-7)
    assert run.log_likelihood == pytest.approx(truth["ll"], abs=1e-6)


@pytest.mark.parametrize("backend", BACKENDS)
def test_rts_smoother_equals_the_textbook_one(backend):
    y, u = linear_record(200, seed=1)
    kf = make(backend=backend)
    xs, Ps = kf.smooth(kf.filter(y, DT, u=u, x0=X0, P0=P0))
    xs_true, Ps_true = textbook_smoother(textbook_filter(y, u, X0, P0))
    assert np.allclose(xs, xs_true, atol=1e-7)
    assert np.allclose(Ps, Ps_true, atol=1e-8)


@pytest.mark.parametrize("backend", BACKENDS)
def test_ukf_equals_ekf_on_linear_dynamics(backend):
    y, u = linear_record(200, seed=2)
    ekf = make(backend=backend).filter(y, DT, u=u, x0=X0, P0=P0)
    ukf_filter = make(UnscentedKalmanFilter, backend=backend, alpha=0.5, kappa=1.0)
    ukf = ukf_filter.filter(y, DT, u=u, x0=X0, P0=P0)
    assert np.allclose(ukf.x, ekf.x, atol=1e-9)
    assert np.allclose(ukf.P, ekf.P, atol=1e-10)
    assert ukf.log_likelihood == pytest.approx(ekf.log_likelihood, abs=1e-8)
    xs_u, _ = ukf_filter.smooth(ukf)
    xs_e, _ = make(backend=backend).smooth(ekf)
    assert np.allclose(xs_u, xs_e, atol=1e-9)


def test_missing_samples_skip_their_update():
    y, u = linear_record(150, seed=3)
    skip = {0, 7, 8, 50, 149}
    y_missing = y.copy()
    y_missing[list(skip)] = np.nan
    truth = textbook_filter(y, u, X0, P0, skip=skip)
    run = make().filter(y_missing, DT, u=u, x0=X0, P0=P0)
    assert np.allclose(run.x, truth["x"], atol=1e-7)
    assert run.log_likelihood == pytest.approx(truth["ll"], abs=1e-6)
    assert not run.measured[7, 0] and run.measured[6, 0]


@pytest.mark.parametrize("cls", [ExtendedKalmanFilter, UnscentedKalmanFilter])
def test_online_steps_reproduce_the_whole_record_run(cls):
    y, u = linear_record(60, seed=4)
    kf = make(cls)
    run = kf.filter(y, DT, u=u, x0=X0, P0=P0)
    state = kf.start(X0, P0)
    for k in range(len(y)):
        state = kf.update(state, y[k])
        assert np.allclose(state.x, run.x[k], atol=1e-12)
        state = kf.predict(state, u[k], DT)
    assert state.log_likelihood == pytest.approx(run.log_likelihood, abs=1e-9)


def test_a_discrete_time_model_iterates_its_map():
    phi, bd, qd = exact_discretisation(DT)
    y, u = linear_record(120, seed=5)
    rng = np.random.default_rng(0)
    x = rng.normal(size=(200, 2))
    uu = rng.normal(size=(200, 1))
    model = dc.DiscrepancyModel(prior=None, discrete_time=True, optimizer=dc.STLSQ(threshold=0.0),
                                feature_library=dc.PolynomialLibrary(1, include_bias=False),
                                state_names=["x1", "x2"], input_names=["u"])
    model.fit(x, u=uu, x_dot=x @ phi.T + uu @ bd.T)
    kf = ExtendedKalmanFilter(model, outputs=["x1"], process_noise=qd,
                              measurement_noise=R_STD)
    truth = textbook_filter(y, u, X0, P0)
    run = kf.filter(y, u=u, x0=X0, P0=P0)
    assert np.allclose(run.x, truth["x"], atol=1e-8)


def van_der_pol_record(seed, m=400, dt=0.05, q=0.2, r=0.1):
    """A noisy Van der Pol oscillator sampled with the position measured (fine Euler–
    Maruyama steps, the process noise on the velocity)."""
    rng = np.random.default_rng(seed)
    x, fine = np.array([1.5, 0.0]), 20
    ys = []
    for _ in range(m):
        ys.append(x[0] + r * rng.standard_normal())
        for _ in range(fine):
            h = dt / fine
            x = x + h * np.array([x[1], 0.5 * (1 - x[0] ** 2) * x[1] - x[0]])
            x[1] += q * np.sqrt(h) * rng.standard_normal()
    return np.array(ys)[:, None]


@pytest.mark.parametrize("cls", [ExtendedKalmanFilter, UnscentedKalmanFilter])
def test_normalised_innovations_are_chi_squared_on_a_nonlinear_system(cls):
    x1, x2 = symbol("x1"), symbol("x2")
    def nis(r_std):
        kf = cls([x2, 0.5 * (1 - x1 ** 2) * x2 - x1], outputs=["x1"], state_names=["x1", "x2"],
                 process_noise=[0.0, 0.2], measurement_noise=r_std)
        return np.concatenate([kf.filter(van_der_pol_record(seed), 0.05, x0=[1.5, 0.0],
                                         P0=[0.1, 0.1]).normalised_innovations_squared()[20:]
                               for seed in range(12)])

    right = nis(0.1)
    # chi-squared with one degree of freedom: mean 1, variance 2, median 0.455 (4,560 samples)
    assert abs(right.mean() - 1) < 4 * np.sqrt(2 / len(right))
    assert abs(np.mean(right < 0.455) - 0.5) < 0.03
    assert nis(0.05).mean() > 1.5          # a filter that trusts the sensor too much is seen


def test_numpy_and_casadi_agree_on_a_nonlinear_output_map():
    x1, x2 = symbol("x1"), symbol("x2")
    model = [x2, -sp.sin(x1) - 0.1 * x2]
    y = np.sin(van_der_pol_record(6, m=100))
    runs = [ExtendedKalmanFilter(model, outputs=[sp.sin(x1)], state_names=["x1", "x2"],
                                 process_noise=[0.0, 0.1], measurement_noise=0.1,
                                 backend=b).filter(y, 0.05, x0=[0.5, 0], P0=[0.3, 0.3])
            for b in BACKENDS]
    assert np.allclose(runs[0].x, runs[1].x, atol=1e-6)
    assert runs[0].log_likelihood == pytest.approx(runs[1].log_likelihood, rel=1e-7)


def test_a_fitted_model_filters_as_its_own_equations():
    rng = np.random.default_rng(0)
    t = np.arange(2000) * 0.01
    x = np.c_[np.sin(t), np.cos(t)]
    x1, x2 = symbol("x1"), symbol("x2")
    model = dc.DiscrepancyModel(prior=[x2, sp.Integer(0)], optimizer=dc.STLSQ(threshold=0.05))
    model.fit(x, 0.01, x_dot=np.c_[x[:, 1], -x[:, 0]])
    y = x[::5, :1] + 0.01 * rng.standard_normal((400, 1))
    fitted = ExtendedKalmanFilter(model, outputs=["x1"], process_noise=[0, 0.1],
                                  measurement_noise=0.01).filter(y, 0.05, x0=[0, 1], P0=[0.1, 0.1])
    exact = ExtendedKalmanFilter([x2, -x1], outputs=["x1"], state_names=["x1", "x2"],
                                 process_noise=[0, 0.1], measurement_noise=0.01).filter(
        y, 0.05, x0=[0, 1], P0=[0.1, 0.1])
    assert np.allclose(fitted.x, exact.x, atol=1e-6)
    velocity_error = fitted.x[50:, 1] - np.cos(t[::5][50:])           # the unmeasured state
    assert np.sqrt(np.mean(velocity_error ** 2)) < 0.03


def test_a_list_of_records_gives_a_list_of_runs():
    (y1, u1), (y2, u2) = linear_record(50, seed=7), linear_record(80, seed=8)
    kf = make()
    runs = kf.filter([y1, y2], DT, u=[u1, u2], x0=X0, P0=P0)
    assert len(runs) == 2 and runs[1].x.shape == (80, 2)
    assert np.array_equal(runs[1].x, kf.filter(y2, DT, u=u2, x0=X0, P0=P0).x)
