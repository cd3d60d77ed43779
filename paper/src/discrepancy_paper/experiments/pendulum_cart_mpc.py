"""The same campaign on another system: a single pendulum on a cart (not in the paper).

The system is built from its Lagrangian with sympy (``discrepancy.systems.PendulumOnCart``):
the first link of Table 1 on a bearing with real friction (k = 0.01 N m s); its prior has
no joint friction and a motor gain 50 % too high, so the exact discrepancy is
``[0, 0, -k/J dphi + c cos(phi) u, -0.5 u]``. Nothing in the campaign
(:mod:`.campaign`, :mod:`.swingup_task`) knows which system it runs: this module only
states the system, its limits, its sensor and its library.
"""
from __future__ import annotations

import numpy as np
import sympy as sp

from discrepancy import FourierLibrary, PolynomialLibrary
from discrepancy.control import Limits, as_casadi
from discrepancy.symbolic import symbol
from discrepancy.systems.pendulum_on_cart import (
    STATE_NAMES,
    PendulumOnCart,
    PendulumOnCartParameters,
)

from .campaign import CONTROLLERS, learning_from_flawed, nominal, perturbed_study
from .swingup_task import SwingUpTask

NAME = "pendulum-cart-mpc"
RAIL, U_MAX, DU_MAX = 0.2, 15.0, 500.0
TRUE = PendulumOnCartParameters(k=0.01)  # a bearing with friction the prior ignores
NOISE = (1e-3, 5e-4, 2e-2, 5e-3)         # phi (rad), s (m), dphi (rad/s), ds (m/s)
X_HANG = np.array([np.pi, 0.0, 0.0, 0.0])
SPREAD = 0.02                             # perturbed true systems: m, a, I, k within ±2 %


def library():
    """1, the states, sin/cos(phi), u and sin/cos(phi)·u (10 candidate terms)."""
    trig = FourierLibrary(n_frequencies=1, variables=["phi"])
    u = PolynomialLibrary(degree=1, include_bias=False, variables=["u"])
    return PolynomialLibrary(degree=1, variables=list(STATE_NAMES)) + trig + u + trig * u


def pendulum_task() -> SwingUpTask:
    limits = Limits.named(STATE_NAMES, ("u",), states={"s": RAIL}, inputs={"u": U_MAX},
                          rates={"u": DU_MAX})
    return SwingUpTask(state_names=STATE_NAMES, input_names=("u",), x_start=X_HANG,
                       x_goal=np.zeros(4), angles=(0,), rates=(2,), T=1.5, n_intervals=75,
                       substeps=4, balance_time=1.0, Q=(10.0, 20.0, 1.0, 0.1), R=1.0,
                       limits=limits, mpc_backoff={"s": 0.01},
                       mpc_options={"horizon": 20, "substeps": 1, "solver": "rti"},
                       noise_std=np.array(NOISE), log_samples=40, smoothing=2, library=library,
                       kinematics={"phi": "dphi", "s": "ds"})


def perturbed_plants(n: int, seed: int):
    """``[(f, x0)]``: true systems with m, a, I, k within ±2 % and the angle within ±0.02 rad."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        factors = {k: rng.uniform(1 - SPREAD, 1 + SPREAD) for k in ("m", "a", "I", "k")}
        x0 = X_HANG.copy()
        x0[0] += rng.uniform(-0.02, 0.02)
        system = PendulumOnCart(TRUE.scaled(factors))
        out.append((as_casadi(system.equations()), x0))
    return out


def run(out_dir, *, quick: bool = False, verbose=None):
    """Write ``out_dir/pendulum-cart-mpc/``; ``quick``: 3 perturbed systems, learning
    between attempts on the nominal system only."""
    from ..plots.mpc import learning_figure, runs_figure
    from .report import Report

    rep = Report(out_dir, NAME, title="Single pendulum on a cart: the constrained campaign on "
                                      "a second system")
    system, task = PendulumOnCart(TRUE), pendulum_task()
    nom = nominal(task, system.equations(), system.flawed_equations())
    names = nom["hybrid"].get_feature_names()
    learned = {s: {n: float(c) for n, c in zip(names, row, strict=True) if c != 0}
               for s, row in zip(STATE_NAMES, nom["hybrid"].coefficients(), strict=True)}
    g = system.discrepancy_equations()
    exact = [str(e) for e in g]
    phi, u = symbol("phi"), symbol("u")
    exact_u, exact_cos_u = float(g[3].coeff(u)), float(g[2].coeff(u).coeff(sp.cos(phi)))
    plants = perturbed_plants(3 if quick else 20, seed=11)
    learn_on = {"nominal system": (nom["f_true"], X_HANG)}
    if not quick:
        learn_on["perturbed system 0"] = plants[0]
    learning = learning_from_flawed(task, nom, learn_on, seed=60)
    study = perturbed_study(task, nom, plants, seed=9000, max_attempts=4)
    n = study["n_cases"]
    rep.results.update(
        settings={"rail_m": RAIL, "max_abs_u": U_MAX, "max_abs_du_dt": DU_MAX, "T_s": task.T,
                  "balance_time_s": task.balance_time, "noise_std": dict(zip(
                      STATE_NAMES, NOISE, strict=True)), "quick": quick},
        exact_discrepancy=dict(zip(STATE_NAMES, exact, strict=True)),
        exact_coefficients={"u in (ds)'": exact_u, "cos(phi) u in (dphi)'": exact_cos_u},
        learned_from_flawed_attempt=learned, nominal_runs=nom["verdicts"],
        plans={"flawed_cpu_time_s": nom["flawed_plan"].cpu_time,
               "hybrid_cpu_time_s": nom["hybrid_plan"].cpu_time},
        learning_from_flawed_model=learning,
        perturbed_cases={k: v for k, v in study.items() if k != "cpu_times_s"},
        mpc_cpu_ms_per_sample_real_time_iteration={
            "median": float(1e3 * np.median(study["cpu_times_s"]["hybrid + MPC"])),
            "worst": float(1e3 * np.max(study["cpu_times_s"]["hybrid + MPC"]))})
    rep.text(f"Swing-up of a single pendulum (the first link of Table 1, joint friction "
             f"k = {TRUE.k} N m s) on a cart with a "
             f"±{RAIL} m rail, |u| ≤ {U_MAX} m/s², |du/dt| ≤ {DU_MAX} m/s³, in T = {task.T} s, "
             f"then {task.balance_time} s of balancing; measurement noise std {NOISE} on "
             f"{STATE_NAMES}. Success as in `cart-mpc` (angle within 0.05 rad, rate below "
             "0.2 rad/s at the end; rail, input and rate limits kept).")
    rep.text("## Learned from the flawed attempt\n\n| state | exact discrepancy | learned |\n"
             "|---|---|---|\n" + "\n".join(
                 f"| ({s})' | {e} | " + (" ".join(f"{c:+.4g} {t}" for t, c in
                                                  learned[s].items()) or "0") + " |"
                 for s, e in zip(STATE_NAMES, exact, strict=True)))
    cols = ["success", "final_state_reached", "limits_respected", "final_max_angle_error_rad",
            "max_abs_s"]
    rep.text("## Nominal true system")
    rep.table(["controller", *cols], [[k, *[v[c] for c in cols]]
                                      for k, v in nom["verdicts"].items()])
    shown = {k: nom["runs"][k] for k in ("flawed + TVLQR", "hybrid + TVLQR", "hybrid + MPC")}
    rep.figure(runs_figure(shown, angles=(0,), position=1, rail=RAIL, u_max=U_MAX,
                           labels=["φ (rad)"]), "nominal_runs.png",
               "Runs on the nominal true system with noise; limits dotted red")
    rep.text("## Learning between attempts, from the flawed model")
    flat = {f"{k}, {route.split(',')[0]}": v for k, by_route in learning.items()
            for route, v in by_route.items()}
    rep.table(["system, route", "attempts to success", "after each failed attempt: dphi, "
               "cos(phi) u in (dphi)', u in (ds)'"],
              [[k, v["attempts_to_success"] or f"not in {v['attempts_run']}", "; ".join(
                  "{:.4f}, {:.4f}, {:.4f}".format(c["dphi"].get("dphi", 0.0),
                                                  c["dphi"].get("cos(phi) u", 0.0),
                                                  c["ds"].get("u", 0.0))
                  for c in (r["coefficients_after"] for r in v["coefficients_after_each_attempt"])
                  if c)] for k, v in flat.items()])
    rep.figure(learning_figure(flat, {"u in (ds)'": ("ds", "u", exact_u),
                                          "cos(φ) u in (φ̇)'": ("dphi", "cos(phi) u",
                                                                exact_cos_u)}),
               "learning.png", f"Two terms of the discrepancy in the model used at each attempt, "
                               f"over their exact values ({exact_u:.3g} and {exact_cos_u:.4g})")
    rep.text(f"## {n} perturbed true systems (m, a, I, k within ±2 %)")
    rep.table(["controller", "success (limits kept)", "upright at the end (limits ignored)",
               "cart within the rail"],
              [[c, f"{study['success_counts'][c]}/{n}",
                f"{study['final_state_reached_counts'][c]}/{n}",
                f"{study['within_state_bounds_counts'][c]}/{n}"] for c in CONTROLLERS])
    return rep.write()
