"""simulate speed against PySINDy 2.x: the same fitted Lorenz model (degree 3 and 5 libraries),
1e4 output steps, scipy's LSODA at rtol = atol = 1e-12 for both (PySINDy's defaults).

Run: .venv/bin/python benchmarks/bench_simulate.py
"""
from __future__ import annotations

import sys
import warnings
from functools import partial

import numpy as np
import pysindy as ps
from _common import DT, lorenz, lorenz_trajectories, machine, median_time, same, table
from threadpoolctl import threadpool_limits

import discrepancy as dc

warnings.filterwarnings("ignore")
STEPS = 10_000
KW = {"method": "LSODA", "rtol": 1e-12, "atol": 1e-12}


def simulate_ours(model, x0, t):
    return model.simulate(x0, t, **KW)


def simulate_peer(model, x0, t):
    return model.simulate(x0, t, integrator_kws=dict(KW))


def main():
    print("## simulate: DiscrepancyModel vs PySINDy (Lorenz, 1e4 steps)\n")
    print(machine() + "\n")
    xs = list(lorenz_trajectories(10, 10_000, seed=1))
    xds = [lorenz(a) for a in xs]
    t = np.arange(STEPS) * DT
    x0 = xs[0][0]
    rows = []
    for degree in (3, 5):
        ours = dc.DiscrepancyModel(feature_library=dc.PolynomialLibrary(degree=degree),
                                   optimizer=dc.STLSQ(threshold=0.1)).fit(xs, t=DT, x_dot=xds)
        peer = ps.SINDy(feature_library=ps.PolynomialLibrary(degree=degree),
                        optimizer=ps.STLSQ(threshold=0.1)).fit(xs, t=DT, x_dot=xds)
        reps = 3 if degree == 3 else 1
        with threadpool_limits(1, user_api="blas"):
            t_o, x_o = median_time(partial(simulate_ours, ours, x0, t), 3)
            t_p, x_p = median_time(partial(simulate_peer, peer, x0, t), reps)
        rows.append([degree, int((ours.coefficients() != 0).sum()), f"{t_o:.3f}", f"{t_p:.3f}",
                     f"**{t_p / t_o:.1f}x**", same(ours.coefficients(), peer.coefficients()),
                     f"{np.abs(x_o - x_p).max():.1e}"])
        print(f"  degree {degree}: ours {t_o:.3f} s, PySINDy {t_p:.3f} s", file=sys.stderr)
    print(table(["library degree", "active terms", "ours (s)", "PySINDy (s)", "speed-up",
                 "same coefficients", "max |x_ours - x_PySINDy| over 1e4 steps"], rows))
    print("\nMedians of 3 runs (PySINDy at degree 5: one run, it is slow), both in this "
          "process with BLAS pinned to one thread (PySINDy's threaded BLAS made single runs "
          "take 159 s instead of ~70 s on this busy machine). Both use scipy's LSODA; the "
          "trajectories differ by the integrators' own error on a chaotic system over 20 s.")


if __name__ == "__main__":
    main()
