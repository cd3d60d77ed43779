"""A constrained swing-up campaign on any system, with noise: the steps the experiments share.

1. :func:`nominal`: plan on the flawed model, run it with TVLQR on the true system (the
   first attempt; its log teaches the hybrid model), plan on the hybrid model, and run
   every controller on the true system: the real-time MPC and, for timing and success
   beside it, the reference solver (IPOPT); with output feedback, a hybrid model learned
   from the measured states alone, planned on and controlled through a Kalman filter.
2. :func:`learning_from_flawed`: from the flawed model to success by MPC attempts, learning
   from each failed attempt's log (derivatives of the 0.5 ms log, as in the paper, or the
   smoothed 20 ms control log, all states or the measured ones).
3. :func:`perturbed_study`: every controller on perturbed true systems, with
   re-identification from the smoothed control log when an MPC attempt fails.
"""
from __future__ import annotations

import copy

import numpy as np
from tqdm import tqdm

from discrepancy.control import DiscrepancyUpdater, as_casadi, learn_by_attempts
from discrepancy.control.learning import coefficient_table

CONTROLLERS = ("flawed + TVLQR", "hybrid + TVLQR", "hybrid + MPC",
               "hybrid + MPC + re-identification")
REFERENCE = "hybrid + MPC (IPOPT reference)"
OUTPUT_FEEDBACK = ("hybrid + MPC, output feedback",
                   "hybrid + MPC, output feedback + re-identification")
#: how the discrepancy is learned from an attempt's log (learning_from_flawed)
ROUTES = ("derivatives of the 0.5 ms log, all states",
          "smoothed 20 ms log, all states",
          "smoothed 20 ms log, measured states (output feedback)")


def nominal(task, true_equations, flawed_equations, *, reference_run: bool = True) -> dict:
    """Plans, learning from the flawed attempt, and every controller on the nominal system
    (both given as ``(states, inputs, rhs)`` sympy equations); ``reference_run=False``
    (quick runs) builds the reference solver for the perturbed study without running it
    here."""
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
    reference = task.mpc(f_hybrid, reference=True) if task.reference_mpc else None
    if reference is not None and reference_run:
        laws[REFERENCE] = reference.follow(hybrid_plan, tracker=hybrid_tracker)
    for k, (name, law) in enumerate(laws.items()):
        runs[name] = task.run(f_true, law, x_start, seed=2 + k)
    reid = task.smoothed_updater(flawed_eqs, outputs=task.state_names, start=flawed_eqs)
    reid.update_from(runs["flawed + TVLQR"])
    nom = {"f_true": f_true, "flawed_equations": flawed_eqs, "flawed_plan": flawed_plan,
           "flawed_tracker": flawed_tracker, "updater": updater, "hybrid": hybrid,
           "hybrid_plan": hybrid_plan, "hybrid_tracker": hybrid_tracker, "runs": runs,
           "hybrid_mpc": hybrid_mpc, "reference_mpc": reference, "reid_updater": reid,
           "mpc_cpu_times_s": {name: list(law.cpu_times) for name, law in laws.items()
                               if hasattr(law, "cpu_times")},
           "mpc_solve_times_s": list(laws["hybrid + MPC"].solve_times),
           "learned_from_flawed_attempt": {ROUTES[0]: hybrid, ROUTES[1]: reid.models_[-1]}}
    if task.measured:
        nom["output_feedback"] = output_feedback_nominal(task, nom)
        nom["learned_from_flawed_attempt"][ROUTES[2]] = nom["output_feedback"]["model"]
        runs[OUTPUT_FEEDBACK[0]] = nom["output_feedback"]["run"]
    nom["verdicts"] = {k: task.judge(r) for k, r in runs.items()}
    return nom


def output_feedback_nominal(task, nom) -> dict:
    """The hybrid model learned from the flawed attempt's measured states alone (its 20 ms
    control log, smoothed), its plan, and output-feedback MPC on it on the nominal system:
    the filter's process noise is the one the learning chose by likelihood with the prior."""
    updater = task.smoothed_updater(nom["flawed_equations"], outputs=task.measured,
                                    start=nom["flawed_equations"])
    model = updater.update_from(nom["runs"]["flawed + TVLQR"])
    f = as_casadi(model)
    plan = task.plan(f, diagnose=True)
    tracker, mpc = task.tracker(f, plan), task.mpc(f)
    # the level chosen with the prior (the update's first pass): the learned model's own
    # (a tenth of it) fits the nominal plant only (chosen after seeing 1/4 perturbed
    # plants succeed with it in a trial run)
    process_noise = updater.process_noise_passes_[0][-1]
    law = task.output_feedback(task.mpc_law(f, plan, tracker, mpc), model, process_noise)
    run = task.run(nom["f_true"], law, task.x_start, seed=9, outputs=task.outputs)
    return {"updater": updater, "model": model, "plan": plan, "tracker": tracker, "mpc": mpc,
            "process_noise": process_noise, "run": run, "estimates": law.estimates,
            "stds": law.stds,
            "estimation": {k: v.tolist() for k, v in law.estimation_errors(run).items()},
            "controller_cpu_times_s": list(law.cpu_times)}


def attempts_summary(attempts) -> dict:
    """Attempts to success and the learned coefficients after each failed attempt."""
    return {"attempts_to_success": next((a.number for a in attempts if a.success), None),
            "attempts_run": len(attempts),
            "verdicts": [a.result["verdict"] for a in attempts],
            "coefficients_after_each_attempt": coefficient_table(attempts)}


def learning_from_flawed(task, nom, plants: dict, *, seed: int, routes=ROUTES) -> dict:
    """From the flawed model to success by MPC attempts, on each plant ``{name: (f, x0)}``,
    learning by each of ``routes``: ``{plant: {route: summary}}``."""
    out = {}
    flawed = nom["flawed_equations"]
    for k, (name, (f, x0)) in enumerate(tqdm(plants.items(), desc="learning by attempts",
                                             disable=None)):
        out[name] = {}
        for j, route in enumerate(r for r in routes if r != ROUTES[2] or task.measured):
            kw, first = {}, (nom["flawed_plan"], nom["flawed_tracker"], None)
            if route == ROUTES[0]:
                updater = DiscrepancyUpdater(task.template(flawed))
            else:
                outputs = task.state_names if route == ROUTES[1] else task.measured
                updater = task.smoothed_updater(flawed, outputs=outputs, start=flawed)
                kw["log"] = updater.log_of
                if route == ROUTES[2]:
                    kw["process_noise"] = nom["output_feedback"]["process_noise"]
            attempt = task.mpc_attempt(f, x0, seed=seed + 100 * k + 10 * j,
                                       guess=nom["flawed_plan"], first=first, **kw)
            attempts = learn_by_attempts(attempt, updater, first=flawed, max_attempts=5)
            out[name][route] = attempts_summary(attempts)
    return out


def perturbed_study(task, nom, plants, *, seed: int, max_attempts: int = 4) -> dict:
    """Every controller on each perturbed true system ``(f, x0)`` of ``plants``, with noise;
    re-identification: up to ``max_attempts`` MPC attempts, learning from the smoothed
    control logs (all states; the measured ones with output feedback)."""
    rows, cpu = [], {}
    of = nom.get("output_feedback")
    for k, (f, x0) in enumerate(tqdm(plants, desc="perturbed systems", disable=None)):
        s = seed + 1000 * k
        row = {"flawed + TVLQR": task.judge(task.run(f, nom["flawed_tracker"], x0, seed=s)),
               "hybrid + TVLQR": task.judge(task.run(f, nom["hybrid_tracker"], x0, seed=s + 1))}
        reid = copy.deepcopy(nom["reid_updater"])
        attempt = task.mpc_attempt(f, x0, seed=s + 2, guess=nom["hybrid_plan"], log=reid.log_of,
                                   first=(nom["hybrid_plan"], nom["hybrid_tracker"],
                                          nom["hybrid_mpc"]))
        attempts = learn_by_attempts(attempt, reid, first=nom["hybrid"],
                                     max_attempts=max_attempts)
        _record(row, cpu, CONTROLLERS[2:], attempts, "cpu_times_s")
        if nom["reference_mpc"] is not None:
            law = nom["reference_mpc"].follow(nom["hybrid_plan"], tracker=nom["hybrid_tracker"])
            row[REFERENCE] = task.judge(task.run(f, law, x0, seed=s + 3))
            cpu.setdefault(REFERENCE, []).extend(law.cpu_times)
        if of is not None:
            reid = copy.deepcopy(of["updater"])
            attempt = task.mpc_attempt(f, x0, seed=s + 4, guess=of["plan"],
                                       first=(of["plan"], of["tracker"], of["mpc"]),
                                       process_noise=of["process_noise"], log=reid.log_of)
            attempts = learn_by_attempts(attempt, reid, first=of["model"],
                                         max_attempts=max_attempts)
            _record(row, cpu, OUTPUT_FEEDBACK, attempts, "controller_cpu_times_s")
            row[OUTPUT_FEEDBACK[0]]["estimation_rms"] = attempts[0].result["estimation_rms"]
        rows.append(row)
    return _summary(task, rows, cpu)


def _record(row, cpu, names, attempts, clock) -> None:
    """The first attempt's and the last attempt's verdicts, and the first's CPU times."""
    row[names[0]] = attempts[0].result["verdict"]
    row[names[1]] = {**attempts[-1].result["verdict"], "attempts": len(attempts)}
    cpu.setdefault(names[0], []).extend(attempts[0].result[clock])


def _summary(task, rows, cpu) -> dict:
    present = [c for c in (*CONTROLLERS, REFERENCE, *OUTPUT_FEEDBACK) if c in rows[0]]
    counts = {c: int(sum(r[c]["success"] for r in rows)) for c in present}
    failed_flawed = [i for i, r in enumerate(rows) if not r["flawed + TVLQR"]["success"]]
    out = {"n_cases": len(rows), "success_counts": counts,
           "final_state_reached_counts": {c: int(sum(r[c]["final_state_reached"]
                                                     for r in rows)) for c in present},
           "hybrid_mpc_successes_where_flawed_tvlqr_fails": int(sum(
               rows[i]["hybrid + MPC"]["success"] for i in failed_flawed)),
           "cases_where_flawed_tvlqr_fails": len(failed_flawed),
           "within_state_bounds_counts": {c: int(sum(r[c]["within_state_bounds"]
                                                     for r in rows)) for c in present},
           "re_identification_attempts": [r[CONTROLLERS[3]]["attempts"] for r in rows],
           "cases": rows, "cpu_times_s": cpu}
    if OUTPUT_FEEDBACK[0] in rows[0]:
        rms = np.array([r[OUTPUT_FEEDBACK[0]]["estimation_rms"] for r in rows])
        out["estimator_rms_error"] = {
            "mean_over_cases": dict(zip(task.state_names, rms.mean(axis=0).tolist(),
                                        strict=True)),
            "worst_case": dict(zip(task.state_names, rms.max(axis=0).tolist(), strict=True))}
        out["output_feedback_re_identification_attempts"] = [
            r[OUTPUT_FEEDBACK[1]]["attempts"] for r in rows]
    return out
