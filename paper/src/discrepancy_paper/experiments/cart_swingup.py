"""Paper Section IV.C: a swing-up planned on a flawed model fails; the learned discrepancy fixes it.

Loop: plan on the flawed model (T = 2.7 s, paper's Q, R) -> run the plan's held inputs on
the true system with a tight ODE solve -> fit the discrepancy from that failed run ->
replan on the hybrid model (flawed + learned) -> run on the true system, open loop and
with time-varying LQR tracking; then 50 perturbed true systems (robustness study).
"""
from __future__ import annotations

import casadi as ca
import numpy as np

from discrepancy import (
    STLSQ,
    DiscrepancyModel,
    FiniteDifference,
    FourierLibrary,
    PolynomialLibrary,
    SavitzkyGolay,
)
from discrepancy.control import PAPER_Q, PAPER_R, as_casadi, plan_trajectory, replay, tvlqr
from discrepancy.control.replay import interval_defects
from discrepancy.control.sensitivity import parameter_sensitivity, state_transition
from discrepancy.systems.double_pendulum_on_cart import STATE_NAMES, DoublePendulumOnCart

from .cart_report import write_report, write_robustness
from .cart_robustness import robustness_study, swing_errors
from .report import Report

NAME = "cart-swingup"
T, N_INTERVALS, SUBSTEPS = 2.7, 135, 10   # 20 ms holds, 2 ms RK4 steps in the planner
RAIL, U_MAX = 0.5, 20.0                   # cart travel (m) and acceleration (m/s^2) limits
X_HANG = np.array([np.pi, np.pi, 0.0, 0.0, 0.0, 0.0])
X_UP = np.zeros(6)
ID_SAMPLES = 20                           # samples per hold interval: the paper's 1 ms
STIFF = {"Q": (100.0, 100.0, 10.0, 1.0, 1.0, 1.0), "R": 0.1}


def bounds():
    """State bounds ``(6, 2)`` (cart on the rail) and input bounds ``(1, 2)``."""
    xb = np.tile([-np.inf, np.inf], (6, 1))
    xb[2] = [-RAIL, RAIL]
    return xb, np.array([[-U_MAX, U_MAX]])


def make_plan(model, cost, *, guess=None, verbose=None):
    """Swing-up plan from hanging to upright at rest on ``model``."""
    xb, ub = bounds()
    return plan_trajectory(model, x0=X_HANG, xf=X_UP, T=T, n_intervals=N_INTERVALS,
                           substeps=SUBSTEPS, cost=cost, x_bounds=xb, u_bounds=ub,
                           Q=PAPER_Q, R=PAPER_R, initial_guess=guess, verbose=verbose)


def library():
    """States, sin/cos of the angles, u, and sin/cos(angle) * u (16 candidate terms)."""
    trig = FourierLibrary(n_frequencies=1, variables=["phi1", "phi2"])
    u = PolynomialLibrary(degree=1, include_bias=False, variables=["u"])
    return PolynomialLibrary(degree=1, variables=list(STATE_NAMES)) + trig + u + trig * u


def _model(system, differentiation) -> DiscrepancyModel:
    return DiscrepancyModel(prior=system.flawed_equations()[2], feature_library=library(),
                            optimizer=STLSQ(threshold=0.01, alpha=0.0),
                            differentiation_method=differentiation,
                            state_names=list(STATE_NAMES), input_names=["u"])


def fit_discrepancy(system, run, differentiation=None) -> DiscrepancyModel:
    """Fit ``g`` from a run sampled inside each hold interval.

    Each interval is its own trajectory, so no derivative straddles a jump of ``u``
    (``(ds)' = u`` is discontinuous at the grid); inside an interval the motion is
    smooth, and a degree-7 Savitzky–Golay fit over its 21 samples differentiates it
    almost exactly (the data are noise-free).
    """
    us = [np.full((len(x), 1), uk[0]) for x, uk in zip(run.x_dense, run.u, strict=True)]
    if differentiation is None:
        differentiation = SavitzkyGolay(window_length=ID_SAMPLES + 1, polyorder=7, smooth=False)
    model = _model(system, differentiation)
    return model.fit(list(run.x_dense), t=list(run.t_dense), u=us)


def differentiation_ablation(system, run) -> dict:
    """Coefficient errors with other derivative estimates: second-order finite differences
    inside each hold interval, and across the whole run (straddling the input jumps)."""
    out = {"per_interval_finite_difference": identification_summary(
        fit_discrepancy(system, run, FiniteDifference()))}
    t, x = dense(run)
    u = np.append(np.repeat(run.u[:, 0], run.x_dense.shape[1] - 1), run.u[-1, 0])[:, None]
    out["whole_run_finite_difference"] = identification_summary(
        _model(system, FiniteDifference()).fit(x, t=t, u=u))
    return {k: {c: v[c] for c in ("sin_phi1_relative_error", "u_relative_error",
                                  "other_active_terms")} for k, v in out.items()}


def identification_summary(model) -> dict:
    """Identified terms and their errors against the exact ``[-sin(phi1), 0, 0, 0, 0, 0.05 u]``."""
    names = model.get_feature_names()
    coef = model.coefficients()
    terms = {s: {n: float(c) for n, c in zip(names, row, strict=True) if c != 0}
             for s, row in zip(STATE_NAMES, coef, strict=True)}
    c_sin = terms["phi1"].get("sin(phi1)", 0.0)
    c_u = terms["ds"].get("u", 0.0)
    others = [f"({s})': {n}" for s, row in terms.items() for n in row
              if (s, n) not in (("phi1", "sin(phi1)"), ("ds", "u"))]
    return {"identified_terms": terms, "sin_phi1_coefficient": c_sin, "u_coefficient": c_u,
            "sin_phi1_relative_error": abs(c_sin + 1.0), "u_relative_error": abs(c_u - 0.05) / 0.05,
            "other_active_terms": others, "equations": model.equations(precision=8)}


def outcome(run) -> dict:
    """Final errors at T, success, and whether the cart stayed on the rail."""
    out = swing_errors(run.final)
    travel = float(np.max(np.abs(run.x_dense[..., 2])))
    # the planner bounds s at the grid points only; allow 1 mm between them
    out.update(max_cart_travel_m=travel, within_rail=bool(travel <= RAIL + 1e-3),
               max_abs_input=float(np.max(np.abs(run.u))), final_state=run.final.tolist())
    return out


def dense(run):
    """``(t, x)`` of a run at every output sample, in time order."""
    t = np.append(run.t_dense[:, :-1].ravel(), run.t[-1])
    x = np.vstack([run.x_dense[:, :-1].reshape(-1, run.x.shape[1]), run.x[-1]])
    return t, x


def plan_summary(plan, model) -> dict:
    """Solver figures and integration accuracy of a plan on its own model."""
    own = replay(model, plan.x[0], plan.t, plan.u)
    return {"cost": plan.cost, "objective": plan.objective, "ipopt_status": plan.status,
            "ipopt_iterations": plan.iterations, "solve_time_s": plan.solve_time,
            "max_interval_integration_error": float(interval_defects(model, plan).max()),
            "own_model_replay_final_state_error": float(np.max(np.abs(own.final - plan.x[-1]))),
            "open_loop_amplification_norm": float(np.linalg.norm(state_transition(model, plan), 2)),
            "max_cart_travel_m": float(np.max(np.abs(plan.x[:, 2]))),
            "final_time_within_0.2_rad_of_upright_s": time_near_upright(plan)}


def time_near_upright(plan, band=0.2) -> float:
    """How long before T the planned angles stay within ``band`` rad of upright (s)."""
    wrapped = np.abs((plan.x[:, :2] + np.pi) % (2 * np.pi) - np.pi)
    outside = np.flatnonzero(np.any(wrapped >= band, axis=1))
    return float(plan.t[-1] - (plan.t[outside[-1] + 1] if len(outside) else plan.t[0]))


def sensitivity(model, plan, coefficient_error) -> dict:
    """``d x(T) / d c`` for the ``sin(phi1)`` coefficient ``c``, and that times the fit's error."""
    x, u = ca.SX.sym("x", 6), ca.SX.sym("u", 1)
    direction = ca.Function("sin_phi1", [x, u], [ca.vertcat(ca.sin(x[0]), 0, 0, 0, 0, 0)])
    d = parameter_sensitivity(model, direction, plan)
    return {"d_final_state_d_sin_phi1_coefficient": d.tolist(),
            "angle_sensitivity_rad_per_unit_coefficient": float(np.max(np.abs(d[:2]))),
            "predicted_angle_error_from_fitted_coefficient_error":
                float(np.max(np.abs(d[:2])) * abs(coefficient_error))}


def run(out_dir, *, quick: bool = False, verbose=None):
    """Run the whole loop and write ``out_dir/cart-swingup/``; ``quick`` uses 5 perturbed cases
    and a 5 frames/s GIF."""
    from ..plots.cart import snapshots_figure, swingup_gif, time_series_figure

    rep = Report(out_dir, NAME, title="Double pendulum on a cart: swing-up with a learned "
                                      "discrepancy (paper Section IV.C)")
    system = DoublePendulumOnCart()
    f_true, f_flawed = as_casadi(system.equations()), as_casadi(system.flawed_equations())
    _, ub = bounds()

    flawed_plan = make_plan(f_flawed, "tracking", verbose=verbose)
    failed = replay(f_true, X_HANG, flawed_plan.t, flawed_plan.u, samples=ID_SAMPLES)
    model = fit_discrepancy(system, failed)
    print("Discrepancy identified from the failed run:")
    model.print(precision=8)
    ident = identification_summary(model)
    ident["other_differentiation_methods"] = differentiation_ablation(system, failed)
    f_hybrid = model.to_casadi()

    hybrid_plan = make_plan(f_hybrid, "tracking", guess=flawed_plan, verbose=verbose)
    effort_plan = make_plan(f_hybrid, "effort", verbose=verbose)
    plans = {"flawed_plan_paper_cost": (flawed_plan, f_flawed),
             "hybrid_plan_paper_cost": (hybrid_plan, f_hybrid),
             "hybrid_plan_min_effort": (effort_plan, f_hybrid)}
    trackers = {"flawed": tvlqr(f_flawed, flawed_plan, Q=PAPER_Q, R=PAPER_R, u_bounds=ub),
                "hybrid": tvlqr(f_hybrid, hybrid_plan, Q=PAPER_Q, R=PAPER_R, u_bounds=ub),
                "effort": tvlqr(f_hybrid, effort_plan, Q=PAPER_Q, R=PAPER_R, u_bounds=ub)}
    strategies = {
        "flawed plan, open loop": (flawed_plan, flawed_plan.u),
        "flawed plan + TVLQR": (flawed_plan, trackers["flawed"]),
        "hybrid plan (paper cost), open loop": (hybrid_plan, hybrid_plan.u),
        "hybrid plan (min effort), open loop": (effort_plan, effort_plan.u),
        "hybrid plan (paper cost) + TVLQR": (hybrid_plan, trackers["hybrid"]),
        "hybrid plan (min effort) + TVLQR": (effort_plan, trackers["effort"]),
    }
    runs = {name: replay(f_true, X_HANG, p.t, law, samples=4) for name, (p, law) in
            strategies.items()}
    runs["flawed plan + stiff TVLQR"] = replay(
        f_true, X_HANG, flawed_plan.t, tvlqr(f_flawed, flawed_plan, u_bounds=ub, **STIFF),
        samples=4)
    outcomes = {name: outcome(r) for name, r in runs.items()}
    for name, o in outcomes.items():
        print(f"{name:40s} {'success' if o['success'] else 'FAIL   '} final |phi1| "
              f"{o['phi1']:.2e} |phi2| {o['phi2']:.2e} |dphi1| {o['dphi1']:.2e} "
              f"|dphi2| {o['dphi2']:.2e} rad(/s); cart travel {o['max_cart_travel_m']:.2f} m")

    coefficient_error = ident["sin_phi1_coefficient"] + 1.0
    sens = {"hybrid_plan_paper_cost": sensitivity(f_hybrid, hybrid_plan, coefficient_error),
            "hybrid_plan_min_effort": sensitivity(f_hybrid, effort_plan, coefficient_error)}
    study = robustness_study(strategies, n_cases=5 if quick else 50, seed=2024,
                             x_hang=X_HANG, rail=RAIL)

    rep.results.update(identification=ident,
                       plans={k: plan_summary(p, m) for k, (p, m) in plans.items()},
                       runs_on_true_system=outcomes, sensitivity=sens, robustness=study,
                       settings={"T_s": T, "n_intervals": N_INTERVALS, "rk4_substeps": SUBSTEPS,
                                 "cart_rail_m": RAIL, "max_abs_acceleration": U_MAX,
                                 "identification_samples_per_interval": ID_SAMPLES,
                                 "tvlqr_weights": "paper Q, R; terminal 100 Q",
                                 "stiff_tvlqr_weights": STIFF, "quick": quick})
    write_report(rep, rep.results)
    pick = ["flawed plan, open loop", "flawed plan + TVLQR", "hybrid plan (paper cost) + TVLQR",
            "hybrid plan (min effort), open loop", "hybrid plan (paper cost), open loop"]
    rep.figure(snapshots_figure({k: dense(runs[k]) for k in pick}, system.points, rail=RAIL),
               "swingup_snapshots.png", "Pendulum every 0.15 s on the true system (paper Fig. 6)")
    ts = {k: (*dense(runs[k]), runs[k].t[:-1], runs[k].u[:, 0]) for k in pick[:4]}
    pl = {f"plan: {k}": (p.t, p.x, p.t[:-1], p.u[:, 0]) for k, (p, _) in plans.items()
          if k != "hybrid_plan_paper_cost"}
    rep.figure(time_series_figure(ts, plans=pl), "time_series.png",
               "Runs on the true system (solid) and plans (dashed)")
    write_robustness(rep, study)
    gif = {k: dense(runs[k]) for k in pick[:4]}
    swingup_gif(rep.dir / "swingup.gif", gif, system.points, rail=RAIL,
                fps=5 if quick else 20)   # quick: a quarter of the frames (the GIF's CPU time)
    rep.text("![Runs side by side](swingup.gif)")
    return rep.write()
