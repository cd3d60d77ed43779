"""Fit speed against PySINDy 2.x in one process: Lorenz, polynomial degree 3 and 5,
m = 1e4, 1e5, 1e6 samples, with x_dot given and end to end (finite differences), plus a
profile of the m = 1e6, degree 5 fit against its floor (one pass over the data plus one
m p^2 product).

Run: .venv/bin/python benchmarks/bench_fit.py [--quick]
"""
from __future__ import annotations

import sys
import time
import warnings
from functools import partial

import numpy as np
import pysindy as ps
from _common import DT, lorenz, lorenz_trajectories, machine, median_time, same, table
from threadpoolctl import threadpool_limits

import discrepancy as dc
import discrepancy.fitting.accumulate as accumulate_module
from discrepancy.data.trajectory import as_trajectories
from discrepancy.fitting.accumulate import BLOCK_ROWS, default_threads, single_threaded_blas

warnings.filterwarnings("ignore")


def data(m: int):
    n_traj = max(1, m // 10_000)
    x = lorenz_trajectories(n_traj, m // n_traj, seed=m)
    xs = list(x)
    return xs, [lorenz(a) for a in xs]


def ours(degree, xs, xds):
    model = dc.DiscrepancyModel(feature_library=dc.PolynomialLibrary(degree=degree),
                                optimizer=dc.STLSQ(threshold=0.1))
    return model.fit(xs, t=DT, x_dot=xds).coefficients()


def peer(degree, xs, xds):
    model = ps.SINDy(feature_library=ps.PolynomialLibrary(degree=degree),
                     optimizer=ps.STLSQ(threshold=0.1))
    return np.asarray(model.fit(xs, t=DT, x_dot=xds).coefficients())


def profile(xs, xds, reps=5):
    """Seconds per phase of the m = 1e6, degree 5 fit with x_dot given."""
    lib = dc.PolynomialLibrary(degree=5).fit(["x1", "x2", "x3"])
    p = lib.n_features_
    x, xd = np.vstack(xs), np.vstack(xds)
    m = x.shape[0]
    blocks = [x[s:s + BLOCK_ROWS] for s in range(0, m, BLOCK_ROWS)]
    # as the accumulator does: rows of A = [Θ | y]ᵀ in a reused buffer, then A Aᵀ
    buffer = np.empty((p + 3, BLOCK_ROWS))
    lib.transform(blocks[0], out=buffer[:p].T)
    buffer[p:] = xd[:BLOCK_ROWS].T
    model = dc.DiscrepancyModel(feature_library=lib, optimizer=dc.STLSQ(threshold=0.1))
    model.fit(xs, t=DT, x_dot=xds)
    stats = model.statistics_
    big = np.asfortranarray(np.random.default_rng(0).standard_normal((65536, p)))
    with single_threaded_blas():
        phases = {
            "validation (as_trajectories)": median_time(
                lambda: as_trajectories(xs, DT, None, xds), reps)[0],
            "residual y = x_dot - prior": median_time(
                lambda: [model.residual(tr) for tr in as_trajectories(xs, DT, None, xds)],
                reps)[0],
            "library Θ, 4096-row blocks": median_time(
                lambda: [lib.transform(b, out=buffer[:p, :b.shape[0]].T) for b in blocks],
                reps)[0],
            "A Aᵀ products (ΘᵀΘ, Θᵀy, yᵀy at once)": median_time(
                lambda: [buffer @ buffer.T for _ in blocks], reps)[0],
            "STLSQ on the 56×56 system": median_time(
                lambda: dc.STLSQ(threshold=0.1).fit_gram(stats.gram, stats.rhs), reps)[0],
        }
        t_big = median_time(lambda: big.T @ big, reps)[0]
    total = median_time(lambda: ours(5, xs, xds), reps)[0]
    accumulate_module.default_threads = lambda: 1
    single = median_time(lambda: ours(5, xs, xds), reps)[0]
    accumulate_module.default_threads = default_threads
    gflops = 2 * 65536 * p * p / t_big / 1e9
    floor = 2 * m * p * p / (gflops * 1e9)
    rows = [[k, f"{v:.3f}", f"{100 * v / single:.0f}%"] for k, v in phases.items()]
    rows.append(["sum of the phases above", f"{sum(phases.values()):.3f}",
                 f"{100 * sum(phases.values()) / single:.0f}%"])
    rows.append(["**whole fit, 1 thread**", f"{single:.3f}", "100%"])
    rows.append([f"**whole fit, {default_threads()} threads** (default)", f"{total:.3f}", ""])
    note = (f"Floor: ΘᵀΘ is 2·m·p² = {2 * m * p * p / 1e9:.1f} GFlop; one core runs a large "
            f"ΘᵀΘ at {gflops:.0f} GFlop/s here, so the product alone needs {floor:.3f} s on one "
            f"core ({floor / 2:.3f} s on two). The whole fit takes {single:.3f} s on one "
            f"thread, {single / floor:.1f}x the one-core floor, and {total:.3f} s with "
            f"{default_threads()} threads. Shares are of the one-thread fit; each phase is "
            "timed alone (BLAS pinned to one thread), so they need not add up exactly.")
    return table(["phase (m = 1e6, degree 5, x_dot given)", "seconds", "share of fit"],
                 rows) + "\n\n" + note


def main(quick: bool = False):
    print("## Fit: DiscrepancyModel vs PySINDy (Lorenz, STLSQ threshold 0.1)\n")
    print(machine() + "\n")
    sizes = [] if "--profile" in sys.argv else [10_000, 100_000] if quick else \
        [10_000, 100_000, 1_000_000]
    rows = []
    for m in sizes:
        xs, xds = data(m)
        reps = 5 if m <= 100_000 else 3
        for degree in (3, 5):
            for mode in ("x_dot given", "end to end"):
                given = xds if mode == "x_dot given" else None
                t_o, c_o = median_time(partial(ours, degree, xs, given), reps)
                t_p, c_p = median_time(partial(peer, degree, xs, given), reps)
                with threadpool_limits(1, user_api="blas"):
                    t_1, _ = median_time(partial(peer, degree, xs, given), reps)
                rows.append([f"{m:.0e}", degree, mode, f"{t_o:.4f}", f"{t_p:.4f}",
                             f"**{t_p / t_o:.1f}x**", f"{t_1:.4f}", f"{t_1 / t_o:.1f}x",
                             same(c_o, c_p)])
                print(f"  m={m:.0e} degree={degree} {mode}: ours {t_o:.4f} s, PySINDy {t_p:.4f} s"
                      f" (1 BLAS thread: {t_1:.4f} s)", file=sys.stderr)
    print(table(["m", "degree", "fit", "ours (s)", "PySINDy as is (s)", "speed-up",
                 "PySINDy, 1 BLAS thread (s)", "speed-up", "same coefficients (max diff)"],
                rows))
    print("\nMedians of 5 (m <= 1e5) or 3 (m = 1e6) runs each, both in this process, on the "
          "same data (m/1e4 trajectories of 1e4 samples at dt = 0.002, RK4). PySINDy is run "
          "as installed (threaded OpenBLAS, which slows down badly when other processes load "
          "the cores) and again with BLAS pinned to one thread, the fairer comparison on a "
          "busy machine.\n")
    if not quick or "--profile" in sys.argv:
        xs, xds = data(1_000_000)
        print("### Where the time goes\n")
        print(profile(xs, xds))


if __name__ == "__main__":
    t0 = time.time()
    main(quick="--quick" in sys.argv)
    print(f"\n(bench_fit ran in {time.time() - t0:.0f} s)", file=sys.stderr)
