"""Double pendulum on a cart: constrained swing-up by MPC on the hybrid model, with noise.

The paper's loop with the limits a rig has (a ±0.5 m rail, |u| <= 20 m/s², |du/dt| <= 500
m/s³) and noisy measurements: plan on the flawed model, run it with TVLQR on the true
system, learn the discrepancy from the log, plan on the hybrid model, then track it and
balance with TVLQR or with nonlinear MPC. Then (1) learning between attempts, starting
from the flawed model, on the nominal and on perturbed true systems, and (2) the 50
perturbed true systems of ``cart-swingup`` with every controller, judged with the limits.
"""
from __future__ import annotations

import numpy as np

from discrepancy.control import PAPER_Q, PAPER_R, Limits
from discrepancy.systems.double_pendulum_on_cart import STATE_NAMES, DoublePendulumOnCart

from .campaign import learning_from_flawed, nominal, perturbed_study
from .cart_mpc_settings import (
    DU_MAX,
    INITIAL_STD,
    KINEMATICS,
    MAX_ATTEMPTS,
    MEASURED,
    NOISE,
    RAIL,
    U_MAX,
    X_HANG,
)
from .cart_robustness import PerturbedPlants, perturbed_cases
from .cart_swingup import library
from .swingup_task import SwingUpTask

NAME = "cart-mpc"


def cart_task() -> SwingUpTask:
    """The cart's campaign settings (the paper's T, Q, R; limits; sensor noise)."""
    limits = Limits.named(STATE_NAMES, ("u",), states={"s": RAIL}, inputs={"u": U_MAX},
                          rates={"u": DU_MAX})
    return SwingUpTask(state_names=STATE_NAMES, input_names=("u",), x_start=X_HANG,
                       x_goal=np.zeros(6), angles=(0, 1), rates=(3, 4), T=2.7,
                       n_intervals=135, substeps=4, balance_time=1.3, Q=PAPER_Q, R=PAPER_R,
                       limits=limits, mpc_backoff={"s": 0.01},
                       mpc_options={"horizon": 20, "substeps": 1, "solver": "rti"},
                       reference_mpc={"solver": "ipopt", "max_iter": 5},
                       noise_std=np.array(NOISE), log_samples=40, smoothing=2,
                       library=library, measured=MEASURED, kinematics=KINEMATICS,
                       initial_std=np.array(INITIAL_STD))


def run(out_dir, *, quick: bool = False, verbose=None):
    """Write ``out_dir/cart-mpc/``; ``quick``: 2 perturbed cases (the first two of
    the 50), learning on one system, the IPOPT reference on the perturbed systems only
    (not also on the nominal one), a 5 frames/s GIF."""
    from .cart_mpc_report import write
    from .report import Report

    rep = Report(out_dir, NAME, title="Double pendulum on a cart: real-time MPC on the "
                                      "hybrid model, state and output feedback, with noise, "
                                      "learning between attempts")
    system, task = DoublePendulumOnCart(), cart_task()
    nom = nominal(task, system.equations(), system.flawed_equations(), reference_run=not quick)
    print("Discrepancy learned from the flawed attempt (noisy log):")
    nom["hybrid"].print(precision=5)
    cases = perturbed_cases(2 if quick else 50, 2024, X_HANG)
    plants = PerturbedPlants()
    learn_on = {"nominal system": (nom["f_true"], X_HANG)}
    for i in range(0 if quick else 1):
        learn_on[f"perturbed system {i}"] = (plants(cases[i][0]), cases[i][1])
    learning = learning_from_flawed(task, nom, learn_on, seed=50)
    study = perturbed_study(task, nom, [(plants(p), x0) for p, x0 in cases], seed=7000,
                            max_attempts=MAX_ATTEMPTS)
    write(rep, task, nom, learning, study, system, quick=quick)
    return rep.write()
