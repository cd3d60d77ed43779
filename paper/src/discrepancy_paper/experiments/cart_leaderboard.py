"""Leaderboard: controllers against a grid of wrong model parameters and measurement noise.

Each cell of the grid is a flawed model: the paper's flawed structure (``+ sin(phi1)`` in
``(phi1)'``, ``0.95 u`` in ``(ds)'``) built with one group of parameters wrong (masses
m1, m2; lengths a1, a2, l1, l2; joint friction k1, k2; motor gain) by a given fraction,
and a measurement-noise level. In every cell the campaign is run from scratch on the
nominal true system: plan on the flawed model and track it with TVLQR (the first attempt,
whose log teaches the hybrid model), then plan on the hybrid model and track it with TVLQR
or MPC; with re-identification, failed MPC attempts add their logs and the model is refitted.
Success is judged with the rail, input and rate limits.
"""
from __future__ import annotations

import numpy as np
from tqdm import tqdm

from discrepancy.control import DiscrepancyUpdater, as_casadi, learn_by_attempts
from discrepancy.systems.double_pendulum_on_cart import CartPendulumParameters, DoublePendulumOnCart

from .campaign import CONTROLLERS
from .cart_mpc import cart_task
from .cart_mpc_settings import MAX_ATTEMPTS, X_HANG

NAME = "cart-leaderboard"
GROUPS = {"masses": ("m1", "m2"), "lengths": ("a1", "a2", "l1", "l2"),
          "friction": ("k1", "k2"), "motor gain": ("gain",)}
LEVELS = {"demo": (-0.3, -0.1, 0.1, 0.3), "full": (-0.3, -0.2, -0.1, 0.1, 0.2, 0.3),
          "quick": (0.3,)}
NOISE_SCALES = {"demo": (1.0, 3.0), "full": (0.0, 1.0, 3.0), "quick": (1.0,)}


class FirstLogDeferred:
    """``updater`` that fits a first ``log`` ``(y, t, u)`` just before the first log it is
    given: the same updates in the same order as fitting that log up front, so the same
    models, but a cell whose first MPC attempt succeeds never pays for the fit it would
    not use (the smoothed fit of the flawed attempt's log is most of a cell's time)."""

    def __init__(self, updater, log):
        self.updater, self.log = updater, log

    def update(self, x, t, *, u):
        """Fit the pending first log if any, then add ``(x, t, u)`` and refit."""
        if self.log is not None:
            y, dt, u_first = self.log
            self.log = None
            self.updater.update(y, dt, u=u_first)
        return self.updater.update(x, t, u=u)


def cell(task, f_true, nominal_plan, group: str, level: float, noise: float, *, seed: int):
    """The four controllers in one cell: ``{controller: verdict}``."""
    params = CartPendulumParameters().scaled({p: 1 + level for p in GROUPS[group]})
    prior = DoublePendulumOnCart(params).flawed_equations()
    f_flawed = as_casadi(prior)
    flawed_plan = task.plan(f_flawed, guess=nominal_plan)
    if flawed_plan is None:
        return {c: {"success": False, "note": "no plan on the flawed model"} for c in CONTROLLERS}
    run = task.run(f_true, task.tracker(f_flawed, flawed_plan), X_HANG, seed=seed,
                   noise_scale=noise, samples=task.log_samples)
    out = {"flawed + TVLQR": task.judge(run)}
    x, t, u = run.measured_trajectories()
    hybrid = DiscrepancyUpdater(task.template(prior)).update(x, t, u=u)
    updater = task.smoothed_updater(prior, outputs=task.state_names, start=prior)
    flawed_log = updater.log_of(run)     # re-identification adds to the flawed log
    f_hybrid = hybrid.to_casadi()
    plan = task.plan(f_hybrid, guess=flawed_plan)
    if plan is None:
        note = {"success": False, "note": "no plan on the hybrid model"}
        return out | {c: dict(note) for c in CONTROLLERS[1:]}
    tracker = task.tracker(f_hybrid, plan)
    out["hybrid + TVLQR"] = task.judge(task.run(f_true, tracker, X_HANG, seed=seed + 1,
                                                noise_scale=noise))
    attempt = task.mpc_attempt(f_true, X_HANG, seed=seed + 2, noise_scale=noise, guess=plan,
                               first=(plan, tracker, None), log=updater.log_of)
    attempts = learn_by_attempts(attempt, FirstLogDeferred(updater, flawed_log), first=hybrid,
                                 max_attempts=MAX_ATTEMPTS)
    out["hybrid + MPC"] = attempts[0].result["verdict"]
    out["hybrid + MPC + re-identification"] = {**attempts[-1].result["verdict"],
                                               "attempts": len(attempts)}
    out["active_terms_first_hybrid"] = hybrid.complexity
    return out


def grid_study(task, *, size: str, seed: int = 300) -> dict:
    """Every cell of the ``size`` grid (``"quick"``, ``"demo"`` or ``"full"``)."""
    system = DoublePendulumOnCart()
    f_true = as_casadi(system.equations())
    nominal_plan = task.plan(as_casadi(system.flawed_equations()))
    levels, noises = LEVELS[size], NOISE_SCALES[size]
    groups = list(GROUPS)[:2] if size == "quick" else list(GROUPS)
    cells = [(g, lv, nz) for nz in noises for g in groups for lv in levels]
    rows = []
    for k, (g, lv, nz) in enumerate(tqdm(cells, desc="wrong-parameter grid", disable=None)):
        rows.append({"group": g, "level": lv, "noise_scale": nz,
                     **cell(task, f_true, nominal_plan, g, lv, nz, seed=seed + 10 * k)})
    maps = {c: {f"noise ×{nz:g}": np.array([[next(r[c]["success"] for r in rows
                                                   if (r["group"], r["level"], r["noise_scale"])
                                                   == (g, lv, nz)) for lv in levels]
                                            for g in groups], dtype=float)
                for nz in noises} for c in CONTROLLERS}
    return {"size": size, "groups": {g: list(GROUPS[g]) for g in groups},
            "levels": list(levels), "noise_scales": list(noises), "cells": rows,
            "success_counts": {c: int(sum(r[c]["success"] for r in rows)) for c in CONTROLLERS},
            "final_state_reached_counts": {c: int(sum(r[c].get("final_state_reached", False)
                                                      for r in rows)) for c in CONTROLLERS},
            "n_cells": len(rows), "maps": maps}


def run(out_dir, *, quick: bool = False, full: bool = False, verbose=None):
    """Write ``out_dir/cart-leaderboard/``; the demo grid by default, ``full`` the whole grid
    (levels ±10, 20, 30 %, noise ×0, 1, 3), ``quick`` two cells."""
    from ..plots.mpc import success_maps_figure
    from .report import Report

    size = "quick" if quick else "full" if full else "demo"
    rep = Report(out_dir, NAME, title="Leaderboard: swing-up controllers against wrong model "
                                      "parameters and measurement noise")
    task = cart_task()
    study = grid_study(task, size=size)
    n = study["n_cells"]
    maps = study.pop("maps")
    rep.results.update(grid=study, success_maps={c: {p: m.tolist() for p, m in v.items()}
                                                 for c, v in maps.items()})
    rep.text(
        f"Grid ({size}; `--full` runs levels ±10/20/30 % and noise ×0/1/3): "
        f"{len(study['groups'])} parameter groups × levels "
        f"{', '.join(f'{100 * v:+.0f} %' for v in study['levels'])} × measurement noise "
        f"{', '.join(f'×{v:g}' for v in study['noise_scales'])} of the `cart-mpc` "
        f"sensor (angles 1 mrad, cart 0.5 mm, rates 0.02 rad/s, cart speed 5 mm/s) = {n} cells. "
        "Each cell is a flawed model: the paper's flawed structure built with one group of "
        "parameters wrong by the level; the true system is nominal (Table 1). Success: upright "
        "at the end of 4 s (both angles within 0.05 rad, rates below 0.2 rad/s) AND the cart "
        "within ±0.5 m, |u| ≤ 20 m/s², |du/dt| ≤ 500 m/s³ throughout. Settings as in `cart-mpc`."
        f" Re-identification: up to {MAX_ATTEMPTS} MPC attempts, each failed one's log added.")
    rep.table(["controller", "success (limits kept)", "upright at the end (limits ignored)"],
              [[c, f"{study['success_counts'][c]}/{n}",
                f"{study['final_state_reached_counts'][c]}/{n}"] for c in CONTROLLERS])
    rows = [f"{g} ({', '.join(p)})" for g, p in study["groups"].items()]
    rep.figure(success_maps_figure(maps, rows=rows,
                                   cols=[f"{100 * v:+.0f}%" for v in study["levels"]],
                                   panels=list(next(iter(maps.values()))),
                                   row_label="wrong group", col_label="parameter error"),
               "success_maps.png", "Success (green) or failure (red) in every cell, per "
                                   "controller (rows) and noise level (columns)")
    rep.table(["group", "level", "noise", *CONTROLLERS, "re-id attempts"],
              [[r["group"], f"{100 * r['level']:+.0f} %", f"×{r['noise_scale']:g}",
                *["yes" if r[c]["success"] else "no" for c in CONTROLLERS],
                r[CONTROLLERS[-1]].get("attempts", "")] for r in study["cells"]])
    return rep.write()
