"""Accuracy, not speed: are the bootstrap's intervals and forecast bands calibrated?

For systems with known discrepancies, fitted with the defaults at several noise levels over
many seeds, how often do the nominal 90 % and 95 % coefficient intervals hold the true
coefficients, and how much of a held-out trajectory (new initial state, noise-free truth) do
the 95 % forecast bands of ``predict_interval`` and ``simulate_interval`` hold.

Run: .venv/bin/python benchmarks/bench_calibration.py [--quick]
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


def vdp(alpha):
    return lambda x, u=None: np.c_[x[:, 1], alpha * (1 - x[:, 0] ** 2) * x[:, 1] - x[:, 0]]


def duffing(beta):
    return lambda x, u=None: np.c_[x[:, 1], -0.2 * x[:, 1] - x[:, 0] - beta * x[:, 0] ** 3]


def lorenz(rho):
    return lambda x, u=None: np.c_[10 * (x[:, 1] - x[:, 0]), x[:, 0] * (rho - x[:, 2]) - x[:, 1],
                                   x[:, 0] * x[:, 1] - 8 / 3 * x[:, 2]]


# name: true rhs, prior, training x0, held-out x0, dt, samples, degree, true terms
SYSTEMS = {
    "Van der Pol": (vdp(0.5), vdp(0.1), [0.5, 0.0], [-0.2, -0.3], 0.01, 2500, 3,
                    {(1, "x2"): 0.4, (1, "x1^2 x2"): -0.4}),
    "Duffing": (duffing(0.5), duffing(0.0), [2.0, 0.0], [1.5, 1.0], 0.01, 3000, 3,
                {(1, "x1^3"): -0.5}),
    "Lorenz": (lorenz(28.0), lorenz(20.0), [-8.0, 8.0, 27.0], [5.0, -5.0, 20.0], 0.002, 5000,
               2, {(1, "x1"): 8.0}),
}


def simulate(rhs, x0, dt, m):
    t = np.arange(m + 1) * dt
    sol = solve_ivp(lambda _, x: rhs(x[None])[0], (0, t[-1]), x0, t_eval=t, method="DOP853",
                    rtol=1e-12, atol=1e-12)
    return t, sol.y.T


def coverage(name, level, seeds, bands):
    rhs, prior, x0, x0_new, dt, m, degree, truth = SYSTEMS[name]
    t, x = simulate(rhs, x0, dt, m)
    t_new, x_new = simulate(rhs, x0_new, dt, min(m, 1000))
    hits = {0.9: 0, 0.95: 0}
    pairs, predict_cover, simulate_cover = 0, [], []
    for seed in seeds:
        noisy = x + level * x.std(axis=0) * np.random.default_rng(seed).standard_normal(x.shape)
        model = dc.DiscrepancyModel(prior=prior, feature_library=dc.PolynomialLibrary(degree))
        model.fit(noisy, t=dt)
        unc = model.bootstrap(noisy, t=dt, seed=seed)
        names = model.get_feature_names()
        for (i, term), value in truth.items():
            j = names.index(term)
            pairs += 1
            for nominal in hits:
                low, high = unc.interval(nominal)
                hits[nominal] += bool(low[i, j] <= value <= high[i, j])
        if bands:
            low, high = model.predict_interval(x_new, uncertainty=unc)
            true_rate = rhs(x_new)
            predict_cover.append(np.mean((low <= true_rate) & (true_rate <= high)))
            low, high = model.simulate_interval(x_new[0], t_new, uncertainty=unc, n_draws=60)
            simulate_cover.append(np.mean((low <= x_new) & (x_new <= high)))
    row = [name, f"{100 * level:g} %", len(seeds), f"{100 * hits[0.9] / pairs:.1f} %",
           f"{100 * hits[0.95] / pairs:.1f} %"]
    row += [f"{100 * np.mean(predict_cover):.1f} %", f"{100 * np.mean(simulate_cover):.1f} %"] \
        if bands else ["", ""]
    return row


def main(quick: bool) -> None:
    n = 4 if quick else 20
    runs = [("Van der Pol", level, True) for level in (0.01, 0.05, 0.1)] + \
        [("Duffing", level, True) for level in (0.05, 0.1)] + \
        [("Lorenz", level, False) for level in (0.05, 0.1)]
    rows = [coverage(name, level, range(n if name != "Lorenz" else n // 2), bands)
            for name, level, bands in runs]
    print(machine())
    print("Defaults (automatic smoothing and threshold), 200 wild block-bootstrap resamples. "
          "Noise: fraction of each state's standard deviation. Coefficient coverage over "
          "seed-coefficient pairs of the true discrepancy; bands: fraction of a held-out "
          "trajectory's samples (new initial state, noise-free) inside the 95 % band of the "
          "hybrid derivatives (predict) and of simulations of 60 resampled models (simulate).\n")
    print(table(["system", "noise", "seeds", "90 % intervals hold truth",
                 "95 % intervals hold truth", "95 % predict band", "95 % simulate band"], rows))


if __name__ == "__main__":
    start = time.perf_counter()
    main("--quick" in sys.argv)
    print(f"\n(total {time.perf_counter() - start:.0f} s)", file=sys.stderr)
