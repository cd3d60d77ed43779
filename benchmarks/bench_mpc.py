"""Benchmark: MPC CPU time per sample of every solver side by side, and cold swing-up plans.

The cart-mpc campaign's settings: a ±0.5 m rail, |u| <= 20, |du/dt| <= 500, measurement
noise; the hybrid model is learned from the flawed attempt's noisy log, as in
``discrepancy reproduce cart-mpc``. Every MPC variant runs the whole closed loop (200
samples of 20 ms) on the nominal true system and on ``--plants`` perturbed ones (the
campaign's first cases), in this one process: the real-time iteration (one Gauss-Newton
SQP step per sample on the condensed QP) with DAQP, qpOASES and OSQP, as CasADi's virtual
machine and as compiled C; IPOPT at 5 iterations (the campaign's former real-time mode) and
converged (the reference); and output feedback (the real-time iteration plus the EKF's
update and prediction). The table gives CPU time per sample (median, 99th percentile,
worst), the control rate the worst sample sustains, the ratio of the medians to IPOPT's,
and the successes. The processor and its load are printed first and last.
Run: ``python benchmarks/bench_mpc.py [--plants 5] [--plans]``.
"""
from __future__ import annotations

import argparse
import os
import time
from dataclasses import replace

import numpy as np
from _common import machine, table

from discrepancy.control import DiscrepancyUpdater, as_casadi
from discrepancy.systems.double_pendulum_on_cart import DoublePendulumOnCart
from discrepancy_paper.experiments.cart_mpc import X_HANG, cart_task
from discrepancy_paper.experiments.cart_robustness import PerturbedPlants, perturbed_cases

VARIANTS = {
    "real-time iteration, DAQP": {"solver": "rti"},
    "real-time iteration, DAQP, compiled C": {"solver": "rti", "compile": True},
    "real-time iteration, qpOASES": {"solver": "rti", "qp_solver": "qpoases"},
    "real-time iteration, OSQP": {"solver": "rti", "qp_solver": "osqp"},
    "IPOPT, at most 5 iterations": {"solver": "ipopt", "max_iter": 5},
    "IPOPT, converged (reference)": {"solver": "ipopt", "max_iter": 100},
}
OUTPUT_FEEDBACK = "output feedback: real-time iteration, DAQP + EKF"


def plans(task, models):
    rows = []
    for name, model in models.items():
        for substeps in (task.substeps, 10):
            plan = replace(task, substeps=substeps).plan(model, diagnose=True)
            rows.append([name, substeps, plan.iterations, f"{plan.cpu_time:.2f}",
                         f"{plan.solve_time:.2f}", "yes" if plan.cpu_time < 5 else "NO"])
    return table(["cold plan (135 intervals, limits)", "RK4 steps / interval", "IPOPT iters",
                  "CPU s", "wall s", "< 5 s CPU"], rows)


def closed_loops(task, plants, hybrid, plan, tracker, process_noise):
    """``{variant: (cpu times per sample (s), successes, build CPU s)}``, every variant on
    every plant."""
    f = hybrid.to_casadi()
    out = {}
    for name, options in [*VARIANTS.items(), (OUTPUT_FEEDBACK, {"solver": "rti"})]:
        t = replace(task, mpc_options={**task.mpc_options, **options})
        start = time.perf_counter()
        mpc = t.mpc(f)
        build = time.perf_counter() - start      # wall: compiling runs in a subprocess
        cpu, ok = [], 0
        for k, (plant, x0) in enumerate(plants):
            law = mpc.follow(plan, tracker=tracker)
            timed, outputs = law, None
            if name == OUTPUT_FEEDBACK:
                timed = law = t.output_feedback(law, hybrid, process_noise)
                outputs = t.outputs
            run = t.run(plant, law, x0, seed=5 + k, outputs=outputs)
            cpu += list(timed.cpu_times)
            ok += t.judge(run)["success"]
        out[name] = (np.array(cpu), ok, build)
    return out


def timing_table(results, n_plants):
    reference = np.median(results["IPOPT, at most 5 iterations"][0])
    rows = []
    for name, (cpu, ok, build) in results.items():
        ms = 1e3 * cpu
        rows.append([name, f"{np.median(ms):.2f}", f"{np.percentile(ms, 99):.2f}",
                     f"{ms.max():.2f}", f"{1e3 / ms.max():.0f}",
                     f"{np.median(cpu) / reference:.3f}", f"{ok}/{n_plants}", f"{build:.1f}",
                     "yes" if np.median(ms) < 5 and ms.max() < 20 else "no"])
    return table(["controller (hybrid model, horizon 20)", "CPU median ms", "CPU p99 ms",
                  "CPU worst ms", "Hz (1/worst)", "median / IPOPT-5's", "successes",
                  "build s (wall)", "median < 5 ms and worst < 20 ms"], rows)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--plants", type=int, default=5, help="perturbed plants besides the "
                                                               "nominal one")
    parser.add_argument("--plans", action="store_true", help="also time cold plans")
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
    learner = task.smoothed_updater(flawed, outputs=task.measured, start=flawed)
    learner.update_from(run)
    print(machine())
    print()
    if args.plans:
        print(plans(task, {"flawed model": f_flawed, "learned hybrid model": f_hybrid}))
        print()
    hybrid_plan = task.plan(f_hybrid)
    cases = perturbed_cases(args.plants, 2024, X_HANG)
    perturbed = PerturbedPlants()
    plants = [(f_true, X_HANG)] + [(perturbed(p), x0) for p, x0 in cases]
    noise = learner.process_noise_passes_[0][-1]   # as in cart-mpc: chosen with the prior
    results = closed_loops(task, plants, hybrid, hybrid_plan,
                           task.tracker(f_hybrid, hybrid_plan), noise)
    print(timing_table(results, len(plants)))
    print(f"\nControl period {1e3 * task.dt:g} ms; CPU time per sample (time.process_time, "
          "what the controller needs on a core of its own; a loaded machine adds waits to "
          "wall-clock time, not to it). Output feedback also counts the EKF's update and "
          "prediction. Compiled C: CasADi's generated code built once by the machine's C "
          "compiler and cached (its build time is the first run's; later runs load it). "
          f"Load average at the end: {', '.join(f'{v:.2f}' for v in os.getloadavg())}.")


if __name__ == "__main__":
    main()
