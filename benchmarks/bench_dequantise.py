"""Accuracy, not speed: friction coefficients of the simulated double pendulum (pendulum-energy
experiment) with and without reconstructing the angles from the encoder counts, on seeds the
experiment does not use (10-59), so the choice of the reconstruction's settings is not tested
on the data it was chosen with.

Run: .venv/bin/python benchmarks/bench_dequantise.py [n_seeds]
"""
from __future__ import annotations

import sys

import numpy as np
from _common import machine, table

from discrepancy.systems.double_pendulum import DoublePendulum
from discrepancy_paper.experiments import pendulum_energy as pe


def k_errors(pend, q, t, method):
    model = pe.dissipation_model(pend, differentiation_method=method).fit(q, t)
    k1, k2 = pe._viscous(model)
    p = pend.parameters
    return 100 * abs(k1 / p.k1 - 1), 100 * abs(k2 / p.k2 - 1)


def main(n_seeds: int = 50) -> None:
    pend = DoublePendulum()
    t = np.arange(int(pe.DURATION * pe.RATE) + 1) / pe.RATE
    methods = {"Savitzky-Golay only": pe._differentiator(dequantise=False),
               "Dequantised + Savitzky-Golay": pe._differentiator()}
    errors = {name: [] for name in methods}
    for seed in range(10, 10 + n_seeds):
        (_, q, _), _ = pe._synthetic_seed(pend, seed, t)
        for name, method in methods.items():
            errors[name].append(k_errors(pend, q, t, method))
    rows = []
    for name, errs in errors.items():
        e = np.array(errs)
        rows.append([name, f"{int(np.sum(e[:, 0] > 1))}/{len(e)}", f"{np.median(e[:, 0]):.3f}",
                     f"{np.sqrt(np.mean(e[:, 0] ** 2)):.3f}", f"{e[:, 0].max():.3f}",
                     f"{int(np.sum(e[:, 1] > 10))}/{len(e)}", f"{e[:, 1].max():.3f}"])
    print(machine())
    print(f"seeds 10-{9 + n_seeds}, 20 s at 1 kHz, 5000-count encoders, dissipation form")
    print(table(["angles", "k1 err > 1 %", "k1 median %", "k1 rms %", "k1 max %",
                 "k2 err > 10 %", "k2 max %"], rows))


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 50)
