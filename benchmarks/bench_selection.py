"""What the default selection by forecasts costs against the old equation-error choice.

The same data are fitted twice with ``DiscrepancyModel(prior=f_m, feature_library=lib)``:
``selection="auto"`` (the default: equation error proposes, forecasts over held-out blocks
decide, the prior alone a candidate) and ``selection="optimizer"`` (the old default:
blocked cross-validation of the derivative fit and the one-standard-error rule). CPU time
(``time.process_time``, median of repeats) of the whole fit, their ratio, and whether each
found the true terms. Noise: Gaussian, 10 % of each state's standard deviation.

Run: .venv/bin/python benchmarks/bench_selection.py [--quick]
"""
from __future__ import annotations

import sys
import time
import warnings

import numpy as np
from _common import machine, table
from scipy.integrate import solve_ivp

import discrepancy as dc

warnings.filterwarnings("ignore")


def duffing(c=0.0, cubic=1.0):
    return lambda x, u=None: np.c_[x[:, 1], -x[:, 0] - cubic * x[:, 0] ** 3 - c * x[:, 1]]


def vdp(alpha):
    return lambda x, u=None: np.c_[x[:, 1], alpha * (1 - x[:, 0] ** 2) * x[:, 1] - x[:, 0]]


def lorenz(rho):
    return lambda x, u=None: np.c_[10 * (x[:, 1] - x[:, 0]), x[:, 0] * (rho - x[:, 2]) - x[:, 1],
                                   x[:, 0] * x[:, 1] - 8 / 3 * x[:, 2]]


def forced(c, cubic):
    return lambda x, u: np.c_[x[:, 1], -x[:, 0] - cubic * x[:, 0] ** 3 - c * x[:, 1] + u[:, 0]]


def forcing(t):
    return 0.5 * (np.sin(0.7 * t) + np.sin(1.9 * t))


# name: true rhs, prior, x0, dt, samples, library, true terms {(state index, name)}, input
SYSTEMS = {
    "Van der Pol, alpha 0.1 vs 0.5": (vdp(0.5), vdp(0.1), [0.5, 0.0], 0.01, 2500,
                                      dc.PolynomialLibrary(3), {(1, "x2"), (1, "x1^2 x2")},
                                      False),
    "Duffing, exact prior": (duffing(), duffing(), [1.5, 0.0], 0.01, 2500,
                             dc.PolynomialLibrary(3), set(), False),
    "Duffing, damping missing": (duffing(0.1), duffing(), [1.5, 0.0], 0.01, 2500,
                                 dc.PolynomialLibrary(3), {(1, "x2")}, False),
    "Lorenz, rho 20 vs 28": (lorenz(28.0), lorenz(20.0), [-8.0, 8.0, 27.0], 0.002, 10000,
                             dc.PolynomialLibrary(2), {(1, "x1")}, False),
    "forced Duffing, cubic and damping missing": (
        forced(0.1, 0.5), forced(0.0, 0.0), [0.0, 0.0], 0.01, 5000, dc.PolynomialLibrary(3),
        {(1, "x1^3"), (1, "x2")}, True),
    "Lorenz, 1e5 samples, degree 3": (lorenz(28.0), lorenz(20.0), [-8.0, 8.0, 27.0], 0.002,
                                      100000, dc.PolynomialLibrary(3), {(1, "x1")}, False),
}


def data(system, seed):
    true, _, x0, dt, m, _, _, has_input = system
    t = np.arange(m) * dt
    f = (lambda s, z: true(z[None], np.array([[forcing(s)]]))[0]) if has_input else \
        (lambda s, z: true(z[None])[0])
    x = solve_ivp(f, (0, t[-1]), x0, t_eval=t, method="DOP853", rtol=1e-10, atol=1e-10).y.T
    x = x + 0.1 * x.std(axis=0) * np.random.default_rng(seed).standard_normal(x.shape)
    return t, x, forcing(t)[:, None] if has_input else None


def fit(system, t, x, u, selection):
    _, prior, _, dt, _, library, _, _ = system
    model = dc.DiscrepancyModel(prior=prior, feature_library=library, selection=selection)
    start = time.process_time()
    model.fit(x, t=dt, u=u)
    return time.process_time() - start, model


def right(model, truth) -> bool:
    names = model.get_feature_names()
    return {(i, names[j]) for i, j in zip(*np.nonzero(model.coef_), strict=True)} == truth


def main(quick: bool = False):
    reps = 1 if quick else 3
    seeds = range(2 if quick else 5)
    rows = []
    for name, system in SYSTEMS.items():
        if quick and "1e5" in name:
            continue
        times = {"auto": [], "optimizer": []}
        hits = {"auto": 0, "optimizer": 0}
        for seed in seeds:
            t, x, u = data(system, seed)
            for selection in times:
                runs = [fit(system, t, x, u, selection) for _ in range(reps)]
                times[selection].append(np.median([r[0] for r in runs]))
                hits[selection] += right(runs[0][1], system[6])
        new, old = np.median(times["auto"]), np.median(times["optimizer"])
        rows.append([name, len(x), f"{1e3 * old:.0f}", f"{1e3 * new:.0f}", f"{new / old:.1f}x",
                     f"{hits['optimizer']}/{len(seeds)}", f"{hits['auto']}/{len(seeds)}"])
    print(machine())
    print()
    print(table(["system", "samples", "old default ms CPU", "forecasts ms CPU",
                 "cost ratio", "true terms (old)", "true terms (forecasts)"], rows))


if __name__ == "__main__":
    main(quick="--quick" in sys.argv)
