"""Benchmark: solve time of each cart swing-up plan (IPOPT via CasADi), replay cost, and
the two numpy forms of the cart dynamics.

Run: ``python benchmarks/bench_swingup.py [--repeats 3]``. Prints tables; the goal is
under 5 s per plan on 2 cores. The hybrid model is the exact discrepancy added to the
flawed model (what the experiment identifies to 1e-8), so this needs no fitting.
"""
from __future__ import annotations

import argparse
import os
import time

import numpy as np

from discrepancy.control import as_casadi, replay
from discrepancy.symbolic import compile_numpy
from discrepancy.systems.double_pendulum_on_cart import DoublePendulumOnCart
from discrepancy_paper.experiments.cart_swingup import X_HANG, make_plan


def timed(fn, repeats):
    times, out = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - start)
    return out, float(np.median(times)), float(np.min(times))


def table(header, rows):
    widths = [max(len(str(r[i])) for r in [header, *rows]) for i in range(len(header))]
    line = "  ".join(f"{{:<{w}}}" for w in widths)
    print(line.format(*header))
    print("  ".join("-" * w for w in widths))
    for r in rows:
        print(line.format(*r))
    print()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    system = DoublePendulumOnCart()
    f_flawed = as_casadi(system.flawed_equations())
    f_hybrid = as_casadi(system.equations())  # flawed + exact discrepancy, simplified

    flawed, *_ = timed(lambda: make_plan(f_flawed, "tracking", verbose=False), 1)
    cases = {
        "flawed model, paper cost": lambda: make_plan(f_flawed, "tracking", verbose=False),
        "hybrid model, paper cost, cold start": lambda: make_plan(f_hybrid, "tracking",
                                                                  verbose=False),
        "hybrid model, paper cost, warm start": lambda: make_plan(
            f_hybrid, "tracking", guess=flawed, verbose=False),
        "hybrid model, min effort": lambda: make_plan(f_hybrid, "effort", verbose=False),
    }
    print(f"cpu count {os.cpu_count()}, repeats {args.repeats}\n")
    rows = []
    for name, fn in cases.items():
        plan, med, best = timed(fn, args.repeats)
        rows.append([name, plan.iterations, f"{plan.solve_time:.2f}", f"{med:.2f}",
                     f"{best:.2f}", "yes" if med < 5 else "NO"])
    table(["plan (135 intervals x 10 RK4)", "IPOPT iters", "IPOPT wall s", "median s",
           "best s", "< 5 s"], rows)

    run_rows = []
    _, med_cv, _ = timed(lambda: replay(f_hybrid, X_HANG, flawed.t, flawed.u), args.repeats)
    _, med_sp, _ = timed(lambda: replay(system.rhs, X_HANG, flawed.t, flawed.u), 1)
    run_rows += [["CVODES (casadi), rtol 1e-12", f"{med_cv:.3f}"],
                 ["DOP853 (scipy) on numpy rhs, rtol 1e-12", f"{med_sp:.3f}"]]
    table(["replay of one plan on the true system", "s"], run_rows)

    rng = np.random.default_rng(0)
    states, inputs, exprs = system.equations()
    names = [s.name for s in [*states, *inputs]]
    explicit = [compile_numpy(e, names) for e in exprs]
    rows = []
    for m in (1, 1000):
        x, u = rng.normal(size=(m, 6)), rng.normal(size=(m, 1))
        z = np.hstack([x, u])
        a, ta, _ = timed(lambda x=x, u=u: system.rhs(x, u), 50)
        b, tb, _ = timed(lambda z=z: np.column_stack([f(z) for f in explicit]), 50)
        rows.append([m, f"{1e6 * ta:.0f}", f"{1e6 * tb:.0f}", f"{np.max(np.abs(a - b)):.1e}"])
    table(["rows", "M, b + Cramer (us)", "explicit sympy accelerations (us)", "max difference"],
          rows)


if __name__ == "__main__":
    main()
