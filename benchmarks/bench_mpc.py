"""Benchmark: cold swing-up plans under limits (CPU s) and MPC solve time per sample.

The cart-mpc campaign's settings: a ±0.5 m rail, |u| <= 20, |du/dt| <= 500, measurement
noise. The hybrid model is learned from the flawed attempt's noisy log, as in
``discrepancy reproduce cart-mpc``. Each MPC variant runs the whole closed loop (200
samples of 20 ms) on the true system; the table gives wall and CPU time per sample
(median, 99th percentile, worst), the control rate the worst sample sustains, and whether
the run succeeded. Run: ``python benchmarks/bench_mpc.py [--repeats 3]``.
"""
from __future__ import annotations

import argparse
import time
from dataclasses import replace

import numpy as np
from _common import machine, table

from discrepancy.control import DiscrepancyUpdater, as_casadi
from discrepancy.systems.double_pendulum_on_cart import DoublePendulumOnCart
from discrepancy_paper.experiments.cart_mpc import X_HANG, cart_task


def plans(task, models, repeats):
    rows = []
    for name, model in models.items():
        for substeps in (task.substeps, 10):
            t = replace(task, substeps=substeps)
            cpu, wall, plan = [], [], None
            for _ in range(repeats):
                start = time.perf_counter()
                plan = t.plan(model, diagnose=True)
                wall.append(time.perf_counter() - start)
                cpu.append(plan.cpu_time)
            rows.append([name, substeps, plan.iterations, f"{np.median(cpu):.2f}",
                         f"{max(cpu):.2f}", f"{np.median(wall):.2f}",
                         "yes" if max(cpu) < 5 else "NO"])
    return table(["cold plan (135 intervals, limits)", "RK4 steps / interval", "IPOPT iters",
                  "CPU s (median)", "CPU s (worst)", "wall s (median)", "< 5 s CPU"], rows)


def mpc_runs(task, f_true, f_hybrid, plan, tracker):
    variants = {"real-time: 5 iterations, horizon 20": {},
                "real-time: 5 iterations, horizon 30": {"horizon": 30},
                "converged: up to 100 iterations, horizon 20": {"max_iter": 100}}
    rows = []
    for name, change in variants.items():
        t = replace(task, mpc_options={**task.mpc_options, **change})
        law = t.mpc_law(f_hybrid, plan, tracker)
        run = t.run(f_true, law, X_HANG, seed=5)
        wall, cpu = 1e3 * np.array(law.solve_times), 1e3 * np.array(law.cpu_times)
        rows.append([name, f"{np.median(wall):.1f}", f"{np.percentile(wall, 99):.1f}",
                     f"{wall.max():.1f}", f"{np.median(cpu):.1f}", f"{cpu.max():.1f}",
                     f"{1e3 / wall.max():.0f}", f"{1e3 / cpu.max():.0f}",
                     f"{int(np.median(law.iterations))}",
                     "yes" if t.judge(run)["success"] else "no"])
    return table(["MPC on the hybrid model (IPOPT, warm start)", "wall median ms", "wall p99 ms",
                  "wall worst ms", "CPU median ms", "CPU worst ms", "Hz (1/worst wall)",
                  "Hz (1/worst CPU)", "median iters", "success"], rows)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    task, system = cart_task(), DoublePendulumOnCart()
    f_true, flawed = as_casadi(system.equations()), system.flawed_equations()
    f_flawed = as_casadi(flawed)
    plan = task.plan(f_flawed)
    run = task.run(f_true, task.tracker(f_flawed, plan), X_HANG, seed=1,
                   samples=task.log_samples)
    x, t, u = run.measured_trajectories()
    hybrid = DiscrepancyUpdater(task.template(flawed)).update(x, t, u=u)
    f_hybrid = hybrid.to_casadi()
    print(machine())
    print()
    print(plans(task, {"flawed model": f_flawed, "learned hybrid model": f_hybrid},
                args.repeats))
    print()
    hybrid_plan = task.plan(f_hybrid)
    print(mpc_runs(task, f_true, f_hybrid, hybrid_plan, task.tracker(f_hybrid, hybrid_plan)))
    print(f"\nControl period {1e3 * task.dt:g} ms. The sustained rate is 1 / the worst time "
          "per sample: on wall-clock time it includes waiting for a CPU on a loaded machine; on "
          "CPU time it is what the solver needs on a core of its own.")


if __name__ == "__main__":
    main()
