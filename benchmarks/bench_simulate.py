"""simulate speed against PySINDy 2.x: the same fitted Lorenz model (degree 3 and 5 libraries),
1e4 output steps, scipy's LSODA at rtol = atol = 1e-12 for both (PySINDy's defaults); and a
model driven by a measured input (forced Duffing, 1e5 samples): our compiled fixed-step RK4,
the same steps in Python, and LSODA in both libraries (timed on a shorter record).

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


def duffing_model():
    """A forced Duffing oscillator fitted (exact derivatives) by both libraries."""
    rng = np.random.default_rng(3)
    t = np.arange(20_000) * 0.01
    u = np.convolve(rng.standard_normal(len(t)), np.ones(30) / 30, mode="same")[:, None]
    x = np.zeros((len(t), 2))
    for i in range(len(t) - 1):                       # explicit Euler data: fine for a fit
        v = x[i]
        x[i + 1] = v + 0.01 * np.array([v[1], -v[0] - 0.1 * v[1] - 0.5 * v[0] ** 3 + u[i, 0]])
    xd = np.c_[x[:, 1], -x[:, 0] - 0.1 * x[:, 1] - 0.5 * x[:, 0] ** 3 + u[:, 0]]
    ours = dc.DiscrepancyModel(feature_library=dc.PolynomialLibrary(3),
                               optimizer=dc.STLSQ(threshold=0.05)).fit(x, t=t, u=u, x_dot=xd)
    peer = ps.SINDy(feature_library=ps.PolynomialLibrary(degree=3),
                    optimizer=ps.STLSQ(threshold=0.05)).fit(x, t=t, u=u, x_dot=xd)
    return ours, peer, t, u


def measured_input():
    print("\n## simulate with a measured input (forced Duffing, 2 states, degree-3 library)\n")
    ours, peer, t, u = duffing_model()
    long, short = 100_000, 2_000
    t_long = np.arange(long) * 0.01
    u_long = np.resize(u, (long, 1))
    rows = []
    for label, call, samples in (
            ("ours, rk4 compiled (CasADi)", lambda: ours.simulate(
                [0, 0], t_long, u=u_long, method="rk4", substeps=4), long),
            ("ours, rk4 in Python", lambda: ours.simulate(
                [0, 0], t[:short], u=u[:short], method="rk4", substeps=4, compiled=False), short),
            ("ours, LSODA", lambda: ours.simulate([0, 0], t[:short], u=u[:short]), short),
            ("PySINDy, LSODA", lambda: peer.simulate([0, 0], t[:short], u=u[:short]), short)):
        seconds, _ = median_time(call, 3 if samples == long else 1)
        rows.append([label, samples, f"{seconds:.3f}", f"{1e6 * seconds / samples:.2f}"])
    per = [float(r[3]) for r in rows]
    for r, p in zip(rows, per, strict=True):
        r.append(f"**{p / per[0]:.0f}x**" if p != per[0] else "1x")
    print(table(["how", "samples", "seconds", "µs per sample", "slower than compiled"], rows))
    print("\nThe Python and LSODA runs are timed on 2,000 samples (per-sample cost is "
          "constant); LSODA steps through the input's kink at every sample.")


if __name__ == "__main__":
    main()
    measured_input()
