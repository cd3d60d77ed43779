"""Control with (hybrid) models: CasADi trajectory optimisation, TVLQR tracking, nonlinear
MPC, closed loops with noise and limits, learning the discrepancy between attempts.

Every function takes CasADi dynamics ``f(x (n,1), u (r,1)) -> xdot (n,1)``, or a
model that exports itself (``to_casadi()``), or ``(states, inputs, rhs)`` sympy equations.
"""
# isort: off
from .dynamics import as_casadi, from_equations, rk4_step  # first: checks that casadi is here
# isort: on
from .closed_loop import ClosedLoopRun, closed_loop
from .learning import Attempt, DiscrepancyUpdater, learn_by_attempts
from .limits import Limits
from .mpc import MPC, MPCLaw, MPCSolution
from .output_feedback import OutputFeedback
from .reidentification import SmoothedLogUpdater
from .replay import Run, interval_defects, replay, swing_up_errors
from .sensitivity import parameter_sensitivity, state_transition
from .tracking import Tracker, linearise, stationary_lqr, tvlqr
from .trajectory import PAPER_Q, PAPER_R, Plan, plan_trajectory

__all__ = ["MPC", "PAPER_Q", "PAPER_R", "Attempt", "ClosedLoopRun", "DiscrepancyUpdater",
           "Limits", "MPCLaw", "MPCSolution", "OutputFeedback", "Plan", "Run",
           "SmoothedLogUpdater", "Tracker", "as_casadi",
           "closed_loop", "from_equations", "interval_defects", "learn_by_attempts",
           "linearise", "parameter_sensitivity", "plan_trajectory", "replay", "rk4_step",
           "state_transition", "stationary_lqr", "swing_up_errors", "tvlqr"]
