"""Accuracy, not speed: the block fit of the dissipation form with each block's energy loss
taken between block means (ours) or between single samples at the block edges (the
estimator it replaced, kept here only as the reference), and the cumulative fit, on the
simulated pendulum-energy swings (seeds 10-29, Savitzky-Golay only, 2 s blocks).

Run: .venv/bin/python benchmarks/bench_block_fit.py [n_seeds]
"""
from __future__ import annotations

import sys
from contextlib import contextmanager

import numpy as np
from _common import machine, table

from discrepancy.energy import regression
from discrepancy.systems.double_pendulum import DoublePendulum
from discrepancy_paper.experiments import pendulum_energy as pe

TRUE_TERMS = {"viscous joint 1", "viscous joint 2"}


def edge_sample_statistics(features, target, block, weights=None):
    """The replaced block fit: losses between single samples ``target[::block]``."""
    idx = np.arange(0, len(target), block)
    loss, gained = np.diff(target[idx]), np.diff(features[idx], axis=0)
    w = 1.0 / np.maximum(np.abs(loss), 1e-3 * np.max(np.abs(loss))) if weights is None \
        else weights
    d, y = gained * w[:, None], loss * w
    return regression.Statistics(d.T @ d, d.T @ y, float(y @ y), float(target.mean()),
                                 features.mean(axis=0))


ours = regression.block_statistics


@contextmanager
def fit_with(function):
    regression.block_statistics = function
    try:
        yield
    finally:
        regression.block_statistics = ours


def errors(pend, q, t, block_seconds):
    model = pe.dissipation_model(pend, block_seconds=block_seconds,
                                 differentiation_method=pe._differentiator(dequantise=False))
    model.fit(q, t)
    k1, k2 = pe._viscous(model)
    p = pend.parameters
    right = {term.name for term in model.terms_} == TRUE_TERMS
    return right, 100 * abs(k1 / p.k1 - 1), 100 * abs(k2 / p.k2 - 1)


def main(n_seeds: int = 20) -> None:
    pend = DoublePendulum()
    t = np.arange(int(pe.DURATION * pe.RATE) + 1) / pe.RATE
    variants = {"2 s blocks, loss between block means (ours)": (ours, 2.0),
                "2 s blocks, loss between edge samples (replaced)": (edge_sample_statistics, 2.0),
                "cumulative (the experiment's fit)": (ours, None)}
    found = {name: [] for name in variants}
    for seed in range(10, 10 + n_seeds):
        (_, q, _), _ = pe._synthetic_seed(pend, seed, t)
        for name, (function, block) in variants.items():
            with fit_with(function):
                found[name].append(errors(pend, q, t, block))
    rows = []
    for name, res in found.items():
        right = np.array([r[0] for r in res])
        e = np.array([r[1:] for r in res])
        rows.append([name, f"{int(right.sum())}/{len(res)}",
                     f"{np.sqrt(np.mean(e[:, 0] ** 2)):.3g}", f"{e[:, 0].max():.3g}",
                     f"{np.sqrt(np.mean(e[:, 1] ** 2)):.3g}", f"{e[:, 1].max():.3g}"])
    print(machine())
    print(f"seeds 10-{9 + n_seeds}, 20 s at 1 kHz, 5000-count encoders, Savitzky-Golay only")
    print(table(["fit", "right terms", "k1 rms %", "k1 max %", "k2 rms %", "k2 max %"], rows))


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 20)
