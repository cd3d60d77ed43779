"""Control with (hybrid) models: CasADi trajectory optimisation, TVLQR tracking, replay.

Every function takes CasADi dynamics ``f(x (n,1), u (r,1)) -> xdot (n,1)``, or a
model that exports itself (``to_casadi()``), or ``(states, inputs, rhs)`` sympy equations.
"""
from .dynamics import as_casadi, from_equations, rk4_step  # first: checks that casadi is here
from .replay import Run, interval_defects, replay, swing_up_errors
from .sensitivity import parameter_sensitivity, state_transition
from .tracking import Tracker, linearise, tvlqr
from .trajectory import PAPER_Q, PAPER_R, Plan, plan_trajectory

__all__ = ["PAPER_Q", "PAPER_R", "Plan", "Run", "Tracker", "as_casadi", "from_equations",
           "interval_defects", "linearise", "parameter_sensitivity", "plan_trajectory", "replay",
           "rk4_step", "state_transition", "swing_up_errors", "tvlqr"]
