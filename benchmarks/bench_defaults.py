"""The no-tuning defaults on systems they were NOT tuned on, and what they cost.

The automatic smoothing (degree, window fraction) and selection were chosen on Van der
Pol, Lorenz, Duffing and Lotka-Volterra. Here four other systems, each with a flawed prior,
are fitted with ``DiscrepancyModel(prior=f_m, feature_library=lib).fit(x, t=dt)`` and
nothing else, at 0-20 % noise (of each state's standard deviation), 10 seeds, against
PySINDy 2.x with its defaults on the same data (given the residual ``x_dot - f_m`` as
``x_dot``, its derivatives by its default finite differences). Then the cost: the
defaults' fit against a plain fit (finite differences, fixed threshold) at m = 1e6.

Run: .venv/bin/python benchmarks/bench_defaults.py [--quick]
"""
from __future__ import annotations

import sys
import time
import warnings

import numpy as np
import pysindy as ps
from _common import DT, lorenz_trajectories, machine, median_time, table
from scipy.integrate import solve_ivp

import discrepancy as dc

warnings.filterwarnings("ignore")


def pendulum(x, u=None, gl=9.81 / 0.5, c=0.3):
    return np.c_[x[:, 1], -gl * np.sin(x[:, 0]) - c * x[:, 1]]


def rossler(x, u=None, c=5.7):
    return np.c_[-x[:, 1] - x[:, 2], x[:, 0] + 0.2 * x[:, 1], 0.2 + x[:, 2] * (x[:, 0] - c)]


def fitzhugh(x, u=None, cubic=True):
    v, w = x[:, 0], x[:, 1]
    return np.c_[v - (v ** 3 / 3 if cubic else 0) - w + 0.5, 0.08 * (v + 0.7 - 0.8 * w)]


def duffing_forced(x, u, beta=1.0, gain=0.3):
    return np.c_[x[:, 1], -0.1 * x[:, 1] - x[:, 0] - beta * x[:, 0] ** 3 + gain * u[:, 0]]


def forcing(t):
    return 0.5 * np.cos(1.2 * t)[:, None]


# name: true rhs, flawed prior, x0, dt, samples, library, true discrepancy {(state, term): c}
SYSTEMS = {
    "pendulum (g/l 20 % low)": (
        pendulum, lambda x, u=None: pendulum(x, gl=0.8 * 9.81 / 0.5), [2.5, 0.0], 0.005, 3000,
        dc.FourierLibrary(1) + dc.PolynomialLibrary(1), {(1, "sin(x1)"): -0.2 * 9.81 / 0.5}),
    "Rossler (c = 5 not 5.7)": (
        rossler, lambda x, u=None: rossler(x, c=5.0), [1.0, 1.0, 0.0], 0.01, 8000,
        dc.PolynomialLibrary(2), {(2, "x3"): -0.7}),
    "FitzHugh-Nagumo (no cubic)": (
        fitzhugh, lambda x, u=None: fitzhugh(x, cubic=False), [-1.0, 1.0], 0.05, 4000,
        dc.PolynomialLibrary(3), {(0, "x1^3"): -1 / 3}),
    "forced Duffing (no cubic, gain 10 % off)": (
        duffing_forced, lambda x, u: duffing_forced(x, u, beta=0.0, gain=0.27), [1.0, 0.0],
        0.01, 4000, dc.PolynomialLibrary(3), {(1, "x1^3"): -1.0, (1, "u"): 0.03}),
}


def simulate(rhs, x0, t, with_input):
    def f(tau, x):
        u = forcing(np.array([tau])) if with_input else None
        return rhs(x[None], u)[0]
    return solve_ivp(f, (t[0], t[-1]), x0, t_eval=t, method="DOP853", rtol=1e-11,
                     atol=1e-11).y.T


def score(coef, names, truth, theta_true):
    expected = np.zeros_like(coef)
    for (i, term), c in truth.items():
        expected[i, names.index(term)] = c
    right = np.array_equal(coef != 0, expected != 0)
    error = np.linalg.norm(theta_true @ (coef - expected).T) / \
        np.linalg.norm(theta_true @ expected.T)
    return right, error


def run_system(name, seeds, noise_levels):
    rhs, prior, x0, dt, m, library, truth = SYSTEMS[name]
    with_input = "forced" in name
    t = np.arange(m) * dt
    x = simulate(rhs, x0, t, with_input)
    u = forcing(t) if with_input else None
    rows = []
    for level in noise_levels:
        ours, peer = [], []
        for seed in range(seeds):
            xn = x + level * x.std(axis=0) * np.random.default_rng(seed).standard_normal(x.shape)
            model = dc.DiscrepancyModel(prior=prior, feature_library=library).fit(xn, t=dt, u=u)
            theta_true = model.feature_library_.transform(x if u is None else np.hstack([x, u]))
            ours.append(score(model.coef_, model.get_feature_names(), truth, theta_true))
            peer.append(pysindy_defaults(model, xn, u, dt, prior, truth, theta_true))
        rows.append([f"{100 * level:.0f} %",
                     f"{sum(r for r, _ in ours)}/{seeds}",
                     f"{100 * np.median([e for _, e in ours]):.2f} %",
                     f"{sum(r for r, _ in peer)}/{seeds}",
                     f"{100 * np.median([e for _, e in peer]):.2f} %"])
    return rows


def pysindy_defaults(model, xn, u, dt, prior, truth, theta_true):
    """PySINDy's defaults (finite differences, STLSQ 0.1) on the residual of the prior,
    with our library's columns as a custom library (same columns, same order)."""
    x_dot = ps.FiniteDifference()._differentiate(xn, dt)
    target = x_dot - prior(xn, u)
    theta = model.feature_library_.transform(xn if u is None else np.hstack([xn, u]))
    opt = ps.STLSQ()
    opt.fit(theta, target)
    return score(opt.coef_, model.get_feature_names(), truth, theta_true)


def cost(m: int):
    n_traj = max(1, m // 10_000)
    xs = list(lorenz_trajectories(n_traj, m // n_traj, seed=m))
    plain = dc.DiscrepancyModel(feature_library=dc.PolynomialLibrary(5),
                                optimizer=dc.STLSQ(threshold=0.1),
                                differentiation_method=dc.FiniteDifference())
    auto = dc.DiscrepancyModel(feature_library=dc.PolynomialLibrary(5))
    t_plain, _ = median_time(lambda: plain.fit(xs, t=DT), 3)
    t_auto, fitted = median_time(lambda: auto.fit(xs, t=DT), 3)
    names = fitted.get_feature_names()
    lorenz_terms = {(0, "x1"), (0, "x2"), (1, "x1"), (1, "x2"), (1, "x1 x3"), (2, "x1 x2"),
                    (2, "x3")}
    found = {(i, names[j]) for i, j in zip(*np.nonzero(fitted.coef_), strict=True)}
    return [[f"{m:.0e}", f"{t_plain:.2f} s", f"{t_auto:.2f} s", f"{t_auto / t_plain:.1f}x",
             "yes" if found == lorenz_terms else f"no ({len(found)} terms)",
             str(fitted.differentiation_method_)]]


def main(quick: bool) -> None:
    seeds = 3 if quick else 10
    levels = [0.0, 0.05, 0.2] if quick else [0.0, 0.05, 0.1, 0.2]
    print("## Defaults on systems they were not tuned on\n")
    print(f"{seeds} seeds per noise level; noise as a fraction of each state's standard "
          "deviation; g error = |Θ(x_true)(ξ - ξ_true)| / |Θ(x_true) ξ_true|.\n")
    for name in SYSTEMS:
        print(f"**{name}**\n")
        print(table(["noise", "ours: right terms", "ours: g error", "PySINDy defaults: right "
                     "terms", "PySINDy: g error"], run_system(name, seeds, levels)))
        print()
    print("## Cost of the automatic choices (Lorenz, degree 5, no prior)\n")
    rows = cost(100_000 if quick else 1_000_000)
    print(table(["samples", "plain fit (finite differences, threshold 0.1)", "defaults (auto "
                 "smoothing + CV threshold)", "ratio", "right terms", "chosen smoothing"], rows))
    print()
    print(machine())


if __name__ == "__main__":
    start = time.perf_counter()
    main("--quick" in sys.argv)
    print(f"\n(total {time.perf_counter() - start:.0f} s)", file=sys.stderr)
