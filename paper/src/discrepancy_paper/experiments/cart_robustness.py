"""Robustness of swing-up strategies to perturbed true systems.

Each case draws the link parameters (all of Table 1 except g) independently within
±2 % and the initial angles within ±0.02 rad of hanging; every strategy (a plan and
its input law: held inputs or a tracker) is then run on that true system. A run
succeeds when it ends near upright AND the cart stayed on the rail.
"""
from __future__ import annotations

import casadi as ca
import numpy as np
from tqdm import tqdm

from discrepancy.control import from_equations, replay, swing_up_errors
from discrepancy.systems.double_pendulum_on_cart import CartPendulumParameters, DoublePendulumOnCart

PERTURBED = ("m1", "m2", "a1", "a2", "I1", "I2", "l1", "l2", "k1", "k2")
PARAMETER_SPREAD, ANGLE_SPREAD = 0.02, 0.02
#: the cart may pass the rail's end by this much between the planner's grid points (m)
RAIL_TOLERANCE = 1e-3


def swing_errors(x_final) -> dict:
    """Final errors of the cart pendulum's swing-up, by state name (angles phi1, phi2 at
    indices 0, 1; rates at 3, 4), and success."""
    e = swing_up_errors(x_final, angles=(0, 1), rates=(3, 4))
    return {"phi1": e["angle_0"], "phi2": e["angle_1"], "dphi1": e["rate_3"],
            "dphi2": e["rate_4"], "success": e["success"]}


class PerturbedPlants:
    """CasADi dynamics of perturbed true systems from one compiled parametric function."""

    def __init__(self):
        states, inputs, self.parameters, rhs = DoublePendulumOnCart.parametric_equations()
        self._f = from_equations(states, [*inputs, *self.parameters], rhs)  # f(x, [u; p])
        self._x, self._u = ca.SX.sym("x", len(states)), ca.SX.sym("u", len(inputs))

    def __call__(self, params: CartPendulumParameters) -> ca.Function:
        values = [getattr(params, p.name) for p in self.parameters]
        return ca.Function("f", [self._x, self._u],
                           [self._f(self._x, ca.vertcat(self._u, *values))])


def perturbed_cases(n_cases: int, seed: int, x_hang):
    """``[(parameters, x0)]``: ``n_cases`` random true systems and initial states."""
    rng = np.random.default_rng(seed)
    cases = []
    for _ in range(n_cases):
        factors = {k: rng.uniform(1 - PARAMETER_SPREAD, 1 + PARAMETER_SPREAD) for k in PERTURBED}
        x0 = np.array(x_hang, dtype=float)
        x0[:2] += rng.uniform(-ANGLE_SPREAD, ANGLE_SPREAD, 2)
        cases.append((CartPendulumParameters().scaled(factors), x0))
    return cases


def robustness_study(strategies: dict, *, n_cases: int, seed: int, x_hang, rail) -> dict:
    """Run every strategy ``{name: (plan, law)}`` on ``n_cases`` perturbed true systems.

    Returns success counts and rates (final state near upright and cart within ``rail``),
    how often the final state alone was reached, each case's final max angle error and
    cart travel per strategy, and the drawn cases (parameter factors, initial angle offsets).
    """
    cases = perturbed_cases(n_cases, seed, x_hang)
    plants = PerturbedPlants()
    success = {name: [] for name in strategies}
    reached = {name: [] for name in strategies}
    errors = {name: [] for name in strategies}
    travel = {name: [] for name in strategies}
    for params, x0 in tqdm(cases, desc="perturbed true systems", disable=None):
        f = plants(params)
        for name, (plan, law) in strategies.items():
            run = replay(f, x0, plan.t, law, samples=4)
            e = swing_errors(run.final)
            travel[name].append(float(np.max(np.abs(run.x_dense[..., 2]))))
            reached[name].append(e["success"])
            success[name].append(e["success"] and travel[name][-1] <= rail + RAIL_TOLERANCE)
            errors[name].append(max(e["phi1"], e["phi2"]))
    nominal = CartPendulumParameters()
    return {
        "n_cases": n_cases, "seed": seed,
        "perturbation": {"parameters": list(PERTURBED), "parameter_spread_fraction":
                         PARAMETER_SPREAD, "initial_angle_spread_rad": ANGLE_SPREAD},
        "success_counts": {k: int(sum(v)) for k, v in success.items()},
        "success_rates": {k: float(np.mean(v)) for k, v in success.items()},
        "final_state_reached_counts": {k: int(sum(v)) for k, v in reached.items()},
        "success": success, "final_max_angle_error_rad": errors,
        "max_cart_travel_m": travel, "rail_m": rail,
        "cases": [{"parameter_factors": {k: getattr(p, k) / getattr(nominal, k)
                                         for k in PERTURBED},
                   "initial_angle_offsets_rad": (x0[:2] - np.asarray(x_hang)[:2]).tolist()}
                  for p, x0 in cases],
    }
