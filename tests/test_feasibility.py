"""Plans that cannot be made: the error names the limit or the horizon, with the numbers."""
import re

import casadi as ca
import numpy as np
import pytest

from discrepancy.control import Limits, plan_trajectory
from discrepancy.errors import ConvergenceError, InfeasibleError
from discrepancy.systems import PendulumOnCart


def double_integrator():
    x, u = ca.SX.sym("x", 2), ca.SX.sym("u", 1)
    return ca.Function("f", [x, u], [ca.vertcat(x[1], u)])


def test_a_speed_bound_too_tight_reports_the_least_speed_the_task_needs():
    """Rest to rest over 1 m in T = 2 s on 20 held inputs, input unbounded: the smallest
    top speed jumps to v in the first interval and back in the last, v (T - dt) = 1."""
    T, N = 2.0, 20
    with pytest.raises(InfeasibleError) as info:
        plan_trajectory(double_integrator(), x0=[0, 0], xf=[1, 0], T=T, n_intervals=N,
                        cost="effort", x_bounds=[[-np.inf, np.inf], [-0.3, 0.3]], verbose=False)
    message = str(info.value)
    assert message.startswith("x_bounds are too tight") and "'x2'" in message
    top = float(re.search(r"spans \[[-0-9.e]+, ([-0-9.e]+)\]", message).group(1))
    assert top == pytest.approx(1 / (T - T / N), rel=1e-3)
    assert isinstance(info.value, ValueError)


def test_a_horizon_too_short_for_the_input_limit_names_T():
    """|u| <= 1 covers at most T²/4 = 0.25 m rest to rest in 1 s, so 1 m is out of reach."""
    with pytest.raises(InfeasibleError,
                       match=r"^T = 1 s is too short .* u_bounds \[\[-1.0, 1.0\]\]"):
        plan_trajectory(double_integrator(), x0=[0, 0], xf=[1, 0], T=1.0, n_intervals=20,
                        cost="effort", u_bounds=[[-1, 1]], verbose=False)
    # the same request with 2.1 s is feasible (2.1²/4 > 1)
    plan = plan_trajectory(double_integrator(), x0=[0, 0], xf=[1, 0], T=2.1, n_intervals=20,
                           cost="effort", u_bounds=[[-1, 1]], verbose=False)
    assert np.max(np.abs(plan.u)) <= 1 + 1e-8


def test_a_rail_too_short_for_the_swing_is_named_by_state():
    system = PendulumOnCart()
    limits = Limits.named(system.state_names, system.input_names, states={"s": 0.05},
                          inputs={"u": 15}, rates={"u": 500})
    with pytest.raises(InfeasibleError, match=r"state 's' must stay in \[-0.05, 0.05\]"):
        plan_trajectory(system.equations(), x0=[np.pi, 0, 0, 0], xf=np.zeros(4), T=2.0,
                        n_intervals=100, limits=limits, verbose=False)
    with pytest.raises(InfeasibleError, match=r"x0 puts state 's' at 0.1, outside"):
        plan_trajectory(system.equations(), x0=[np.pi, 0.1, 0, 0], xf=np.zeros(4),
                        limits=limits, verbose=False)
    with pytest.raises(ConvergenceError, match="IPOPT found no plan"):   # no diagnosis asked
        plan_trajectory(system.equations(), x0=[np.pi, 0, 0, 0], xf=np.zeros(4), T=2.0,
                        n_intervals=100, limits=limits, verbose=False, diagnose=False)
