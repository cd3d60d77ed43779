"""Benchmark: Kalman filter steps (CPU per sample) and the estimators' accuracy.

Two systems: a forced Duffing oscillator (2 states, the position measured) and the double
pendulum on a cart of the MPC campaign (6 states; both angles and the cart position
measured with the campaign's noise, 1e-3; velocities estimated), its true equations as the
model, a smooth input and 20 ms samples. For each filter: CPU per online step
(``update`` + ``predict``, median and worst over the record), CPU per sample of ``filter``
over the whole record, and the RMS error of the unmeasured velocities (filtered, and
smoothed by RTS). The peer, measured in the same run, is the extended Kalman filter a user
writes by hand in numpy: analytic Jacobians from sympy (``lambdify``), the mean by one RK4
step, the covariance by ``Φ = I + A h`` and ``Q h``. Run: ``python
benchmarks/bench_estimation.py``.

Whether a moving-horizon estimator would earn its place: for a linear-Gaussian model its
estimate of the current state equals the Kalman filter's, so it can only gain through
nonlinearity over its window or state constraints. The UKF's errors equal to the EKF's
(to three digits) say the linearisation loses nothing at these sample rates, and the
estimation problem has no state constraints; the RTS column shows what hindsight buys (the
smoother uses later samples, which a controller does not have).
"""
from __future__ import annotations

import time

import numpy as np
import sympy as sp
from _common import machine, table

from discrepancy.estimation import ExtendedKalmanFilter, UnscentedKalmanFilter
from discrepancy.systems.double_pendulum_on_cart import DoublePendulumOnCart

DT = 0.02


def duffing():
    pos, vel, u = sp.symbols("pos vel u")
    rhs = [vel, -pos - 0.4 * vel - 0.5 * pos ** 3 + u]
    return ["pos", "vel"], ["u"], [pos, vel, u], rhs, ["pos"], [0.0, 0.05], [1e-3], [1]


def cart():
    system = DoublePendulumOnCart()
    states, inputs, rhs = system.equations()
    names = [s.name for s in states]
    return (names, ["u"], [*states, *inputs], rhs, ["phi1", "phi2", "s"],
            [0, 0, 0, 0.05, 0.05, 0.05], [1e-3] * 3, [3, 4, 5])


def simulate(names, symbols, rhs, q, r_std, steps, seed=0):
    """RK4 at 10 substeps per sample with white process noise, a smooth random input."""
    f = sp.lambdify(symbols, rhs, "numpy")
    rng = np.random.default_rng(seed)
    n = len(names)
    t = np.arange(steps) * DT
    u = 3 * np.sin(1.3 * t) + 2 * np.sin(3.1 * t + 1)
    x = np.zeros(n)
    if n == 6:
        x[:2] = [np.pi - 0.3, np.pi + 0.2]
    out, h = np.empty((steps, n)), DT / 10

    def g(z, v):
        return np.array([float(e) for e in f(*z, v)])

    for k in range(steps):
        out[k] = x
        for _ in range(10):
            k1 = g(x, u[k])
            k2 = g(x + h / 2 * k1, u[k])
            k3 = g(x + h / 2 * k2, u[k])
            x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + g(x + h * k3, u[k]))
            x += np.asarray(q) * np.sqrt(h) * rng.standard_normal(n)
    return t, u[:, None], out


class HandEKF:
    """The peer: a textbook discrete EKF written in numpy."""

    def __init__(self, symbols, rhs, n, measured, q, r):
        x = sp.Matrix(symbols[:n])
        self.f = sp.lambdify(symbols, rhs, "numpy")
        self.A = sp.lambdify(symbols, sp.Matrix(rhs).jacobian(x), "numpy")
        self.H = np.eye(n)[measured]
        self.Q, self.R = np.diag(np.square(q)) * DT, np.diag(np.square(r))
        self.n = n

    def step(self, x, P, y, u):
        S = self.H @ P @ self.H.T + self.R
        K = P @ self.H.T @ np.linalg.inv(S)
        x = x + K @ (y - self.H @ x)
        P = (np.eye(self.n) - K @ self.H) @ P
        filtered = x

        def f(z):
            return np.array(self.f(*z, u), dtype=float).ravel()

        k1 = f(x)
        k2 = f(x + DT / 2 * k1)
        k3 = f(x + DT / 2 * k2)
        x = x + DT / 6 * (k1 + 2 * k2 + 2 * k3 + f(x + DT * k3))
        phi = np.eye(self.n) + DT * np.array(self.A(*filtered, u), dtype=float)
        return filtered, x, phi @ P @ phi.T + self.Q


def online(kf, y, u, x0, P0):
    state, times, xs = kf.start(x0, P0), [], []
    for k in range(len(y)):
        start = time.process_time()
        state = kf.update(state, y[k])
        xs.append(state.x)
        state = kf.predict(state, u[k], DT)
        times.append(time.process_time() - start)
    return np.array(times), np.array(xs)


def rows_for(label, system, steps=500):
    names, inputs, symbols, rhs, outputs, q, r, rates = system
    n = len(names)
    t, u, x = simulate(names, symbols, rhs, q, r, steps)
    measured = [names.index(o) for o in outputs]
    rng = np.random.default_rng(1)
    y = x[:, measured] + np.asarray(r) * rng.standard_normal((steps, len(measured)))
    x0, P0 = x[0], np.full(n, 1e-2)
    rows, peer_time = [], None
    hand = HandEKF(symbols, rhs, n, measured, q, r)
    xs, times, xk, Pk = [], [], x0.copy(), np.diag(P0 ** 2)
    for k in range(steps):
        start = time.process_time()
        filtered, xk, Pk = hand.step(xk, Pk, y[k], u[k, 0])
        times.append(time.process_time() - start)
        xs.append(filtered)
    peer_time = float(np.median(times))
    rows.append([label, "hand-written numpy EKF (peer)", "Euler Φ", f"{1e6 * peer_time:.0f}",
                 f"{1e6 * max(times):.0f}", "", "1.00", _rms(np.array(xs), x, rates), ""])
    for cls, backend, substeps in ((ExtendedKalmanFilter, "casadi", 1),
                                   (ExtendedKalmanFilter, "casadi", 4),
                                   (UnscentedKalmanFilter, "casadi", 1),
                                   (ExtendedKalmanFilter, "numpy", 1)):
        kf = cls(rhs, outputs=outputs, state_names=names, input_names=inputs, process_noise=q,
                 measurement_noise=r, substeps=substeps, u_hold="zoh", backend=backend)
        times, _ = online(kf, y, u, x0, P0)
        start = time.process_time()
        run = kf.filter(y, DT, u=u, x0=x0, P0=P0)
        batch = (time.process_time() - start) / steps
        smoothed, _ = kf.smooth(run)
        rows.append([label, f"{cls.__name__} ({backend})", f"RK4 x {substeps}",
                     f"{1e6 * np.median(times):.0f}", f"{1e6 * times.max():.0f}",
                     f"{1e6 * batch:.0f}", f"{np.median(times) / peer_time:.2f}",
                     _rms(run.x, x, rates), _rms(smoothed, x, rates)])
    return rows


def _rms(estimate, truth, rates) -> str:
    return ", ".join(f"{np.sqrt(np.mean((estimate[50:, i] - truth[50:, i]) ** 2)):.2e}"
                     for i in rates)


def main():
    print(machine())
    print()
    rows = rows_for("Duffing (2 states, pos measured)", duffing()) + \
        rows_for("cart double pendulum (6 states, angles + cart)", cart())
    print(table(["system", "filter", "prediction", "online step CPU µs (median)",
                 "online step CPU µs (worst)", "filter() CPU µs / sample",
                 "online ratio to peer", "RMS error of velocities (filtered)",
                 "RMS error (RTS smoothed)"], rows))


if __name__ == "__main__":
    main()
