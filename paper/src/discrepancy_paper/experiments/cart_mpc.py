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
from .cart_robustness import PerturbedPlants, perturbed_cases
from .cart_swingup import library
from .swingup_task import SwingUpTask

NAME = "cart-mpc"
RAIL, U_MAX, DU_MAX = 0.5, 20.0, 500.0   # m, m/s², m/s³
#: measurement noise std: angles (rad), cart (m), angle rates (rad/s), cart speed (m/s)
NOISE = (1e-3, 1e-3, 5e-4, 2e-2, 2e-2, 5e-3)
X_HANG = np.array([np.pi, np.pi, 0.0, 0.0, 0.0, 0.0])
#: output feedback: the encoders measure the angles and the cart, not the rates
MEASURED = ("phi1", "phi2", "s")
KINEMATICS = {"phi1": "dphi1", "phi2": "dphi2", "s": "ds"}
#: belief about the start (the perturbed cases start within 0.02 rad of hanging, at rest)
INITIAL_STD = (0.02, 0.02, 1e-3, 0.01, 0.01, 0.01)
MAX_ATTEMPTS = 4                          # MPC attempts on a perturbed system, re-id between


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


#: the exact discrepancy of the paper's flawed model: [-sin(phi1), 0, 0, 0, 0, 0.05 u]
EXACT_TERMS = {"phi1": {"sin(phi1)": -1.0}, "ds": {"u": 0.05}}


def identification(model, exact=None) -> dict:
    """The learned terms against the exact discrepancy: every term, how many are spurious
    (not in the exact discrepancy) or missing, and the exact terms' learned coefficients."""
    exact = EXACT_TERMS if exact is None else exact
    names = model.get_feature_names()
    terms = {s: {n: float(c) for n, c in zip(names, row, strict=True) if c != 0}
             for s, row in zip(model.state_names_, model.coefficients(), strict=True)}
    wanted = {(s, t) for s, ts in exact.items() for t in ts}
    found = {(s, t) for s, ts in terms.items() for t in ts}
    return {"identified_terms": terms, "active_terms": model.complexity,
            "spurious_terms": len(found - wanted), "missing_terms": len(wanted - found),
            "exact_terms_learned": {f"{t} in ({s})'": terms.get(s, {}).get(t, 0.0)
                                    for s, t in sorted(wanted)},
            "exact_terms": exact}


def run(out_dir, *, quick: bool = False, verbose=None):
    """Write ``out_dir/cart-mpc/``; ``quick``: 4 perturbed cases, learning on one system."""
    from .cart_mpc_report import write
    from .report import Report

    rep = Report(out_dir, NAME, title="Double pendulum on a cart: real-time MPC on the "
                                      "hybrid model, state and output feedback, with noise, "
                                      "learning between attempts")
    system, task = DoublePendulumOnCart(), cart_task()
    nom = nominal(task, system.equations(), system.flawed_equations())
    print("Discrepancy learned from the flawed attempt (noisy log):")
    nom["hybrid"].print(precision=5)
    cases = perturbed_cases(4 if quick else 50, 2024, X_HANG)
    plants = PerturbedPlants()
    learn_on = {"nominal system": (nom["f_true"], X_HANG)}
    for i in range(0 if quick else 1):
        learn_on[f"perturbed system {i}"] = (plants(cases[i][0]), cases[i][1])
    learning = learning_from_flawed(task, nom, learn_on, seed=50)
    study = perturbed_study(task, nom, [(plants(p), x0) for p, x0 in cases], seed=7000,
                            max_attempts=MAX_ATTEMPTS)
    write(rep, task, nom, learning, study, system, quick=quick)
    return rep.write()
