"""A constrained swing-up campaign on any system, with noise: the steps the experiments share.

1. :func:`nominal`: plan on the flawed model, run it with TVLQR on the true system (the
   first attempt; its log teaches the hybrid model), plan on the hybrid model, and run
   every controller on the true system.
2. :func:`learning_from_flawed`: from the flawed model to success by MPC attempts, learning
   from each failed attempt's log (a sum of Gram statistics).
3. :func:`perturbed_study`: every controller on perturbed true systems, with
   re-identification when the hybrid + MPC attempt fails.
"""
from __future__ import annotations

import copy

from tqdm import tqdm

from discrepancy.control import DiscrepancyUpdater, as_casadi, learn_by_attempts
from discrepancy.control.learning import coefficient_table

CONTROLLERS = ("flawed + TVLQR", "hybrid + TVLQR", "hybrid + MPC",
               "hybrid + MPC + re-identification")


def nominal(task, true_equations, flawed_equations) -> dict:
    """Plans, learning from the flawed attempt, and every controller on the nominal system
    (both given as ``(states, inputs, rhs)`` sympy equations)."""
    f_true, flawed_eqs = as_casadi(true_equations), flawed_equations
    f_flawed = as_casadi(flawed_eqs)
    x_start = task.x_start
    flawed_plan = task.plan(f_flawed, diagnose=True)            # cold start
    flawed_tracker = task.tracker(f_flawed, flawed_plan)
    runs = {"flawed + TVLQR": task.run(f_true, flawed_tracker, x_start, seed=1,
                                       samples=task.log_samples)}
    updater = DiscrepancyUpdater(task.template(flawed_eqs))
    x, t, u = runs["flawed + TVLQR"].measured_trajectories()
    hybrid = updater.update(x, t, u=u)
    f_hybrid = hybrid.to_casadi()
    hybrid_plan = task.plan(f_hybrid, diagnose=True)            # cold start as well
    hybrid_tracker = task.tracker(f_hybrid, hybrid_plan)
    hybrid_mpc = task.mpc(f_hybrid)
    laws = {"flawed + MPC": task.mpc_law(f_flawed, flawed_plan, flawed_tracker),
            "hybrid + TVLQR": hybrid_tracker,
            "hybrid + MPC": task.mpc_law(f_hybrid, hybrid_plan, hybrid_tracker, hybrid_mpc)}
    for k, (name, law) in enumerate(laws.items()):
        runs[name] = task.run(f_true, law, x_start, seed=2 + k)
    mpc = laws["hybrid + MPC"]
    return {"f_true": f_true, "flawed_equations": flawed_eqs, "flawed_plan": flawed_plan,
            "flawed_tracker": flawed_tracker, "updater": updater, "hybrid": hybrid,
            "hybrid_plan": hybrid_plan, "hybrid_tracker": hybrid_tracker, "runs": runs,
            "hybrid_mpc": hybrid_mpc,
            "verdicts": {k: task.judge(r) for k, r in runs.items()},
            "mpc_solve_times_s": list(mpc.solve_times), "mpc_cpu_times_s": list(mpc.cpu_times),
            "mpc_iterations": list(mpc.iterations)}


def attempts_summary(attempts) -> dict:
    """Attempts to success and the learned coefficients after each failed attempt."""
    return {"attempts_to_success": next((a.number for a in attempts if a.success), None),
            "attempts_run": len(attempts),
            "verdicts": [a.result["verdict"] for a in attempts],
            "coefficients_after_each_attempt": coefficient_table(attempts)}


def learning_from_flawed(task, nom, plants: dict, *, seed: int) -> dict:
    """From the flawed model to success by MPC attempts, on each plant ``{name: (f, x0)}``."""
    out = {}
    for k, (name, (f, x0)) in enumerate(tqdm(plants.items(), desc="learning by attempts",
                                             disable=None)):
        attempt = task.mpc_attempt(f, x0, seed=seed + 100 * k, guess=nom["flawed_plan"],
                                   first=(nom["flawed_plan"], nom["flawed_tracker"], None))
        updater = DiscrepancyUpdater(task.template(nom["flawed_equations"]))
        attempts = learn_by_attempts(attempt, updater, first=nom["flawed_equations"],
                                     max_attempts=5)
        out[name] = attempts_summary(attempts)
    return out


def perturbed_study(task, nom, plants, *, seed: int, max_attempts: int = 4) -> dict:
    """Every controller on each perturbed true system ``(f, x0)`` of ``plants``, with noise;
    re-identification: up to ``max_attempts`` MPC attempts."""
    rows, solve_times, cpu_times = [], [], []
    for k, (f, x0) in enumerate(tqdm(plants, desc="perturbed systems", disable=None)):
        s = seed + 1000 * k
        row = {"flawed + TVLQR": task.judge(task.run(f, nom["flawed_tracker"], x0, seed=s)),
               "hybrid + TVLQR": task.judge(task.run(f, nom["hybrid_tracker"], x0, seed=s + 1))}
        attempt = task.mpc_attempt(f, x0, seed=s + 2, guess=nom["hybrid_plan"],
                                   first=(nom["hybrid_plan"], nom["hybrid_tracker"],
                                          nom["hybrid_mpc"]))
        attempts = learn_by_attempts(attempt, copy.deepcopy(nom["updater"]),
                                     first=nom["hybrid"], max_attempts=max_attempts)
        solve_times += attempts[0].result["solve_times_s"]
        cpu_times += attempts[0].result["cpu_times_s"]
        row["hybrid + MPC"] = attempts[0].result["verdict"]
        row["hybrid + MPC + re-identification"] = {**attempts[-1].result["verdict"],
                                                   "attempts": len(attempts)}
        rows.append(row)
    counts = {c: int(sum(r[c]["success"] for r in rows)) for c in CONTROLLERS}
    reached = {c: int(sum(r[c]["final_state_reached"] for r in rows)) for c in CONTROLLERS}
    failed_flawed = [i for i, r in enumerate(rows) if not r["flawed + TVLQR"]["success"]]
    return {"n_cases": len(rows), "success_counts": counts,
            "final_state_reached_counts": reached,
            "hybrid_mpc_successes_where_flawed_tvlqr_fails": int(sum(
                rows[i]["hybrid + MPC"]["success"] for i in failed_flawed)),
            "cases_where_flawed_tvlqr_fails": len(failed_flawed),
            "within_state_bounds_counts": {c: int(sum(r[c]["within_state_bounds"] for r in rows))
                                   for c in CONTROLLERS},
            "re_identification_attempts": [r["hybrid + MPC + re-identification"]["attempts"]
                                           for r in rows],
            "cases": rows, "mpc_solve_times_s": solve_times, "mpc_cpu_times_s": cpu_times}
