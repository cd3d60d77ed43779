"""How much an open-loop plan amplifies errors: first-order sensitivities of its final state.

Along a plan the linearised discrete step ``dx[k+1] = A_k dx[k] + C_k dp`` (``C_k`` the
derivative with respect to model parameters ``p``) is propagated from ``dx[0] = 0``;
the final ``dx[N] / dp`` says how far the open-loop end state moves per unit error
in a coefficient, and ``Φ = A_{N-1} ... A_0`` how much an initial (or integration)
error grows.
"""
from __future__ import annotations

import casadi as ca
import numpy as np

from ..errors import ParameterError, ShapeError
from .dynamics import as_casadi, rk4_step
from .tracking import linearise
from .trajectory import Plan, check_plan


def state_transition(model, plan: Plan) -> np.ndarray:
    """``Φ (n, n)``: final-state change per initial-state change along ``plan``, open loop."""
    A, _ = linearise(model, plan)
    phi = np.eye(A.shape[1])
    for a in A:
        phi = a @ phi
    return phi


def parameter_sensitivity(model, perturbation, plan: Plan) -> np.ndarray:
    """``d x(T) / d c`` ``(n,)`` for the model ``f(x, u) + c * perturbation(x, u)`` at ``c = 0``.

    Args:
        model: the plan's model (anything :func:`~.dynamics.as_casadi` accepts).
        perturbation: CasADi Function ``(x, u) -> (n, 1)``, the direction of the model error,
            e.g. ``[sin(phi1), 0, ...]`` for an error in a ``sin(phi1)`` coefficient.
        plan: the open-loop plan whose held inputs are replayed.
    """
    check_plan(plan)
    f = as_casadi(model)
    n, r = f.size1_in(0), f.size1_in(1)
    if not isinstance(perturbation, ca.Function):
        raise ParameterError(f"perturbation must be a casadi.Function (x, u) -> ({n}, 1); got "
                             f"{type(perturbation).__name__}")
    if perturbation.size_out(0) != (n, 1):
        raise ShapeError(f"perturbation must return ({n}, 1); got {perturbation.size_out(0)}")
    x, u, c = ca.SX.sym("x", n), ca.SX.sym("u", r), ca.SX.sym("c")
    fc = ca.Function("fc", [x, ca.vertcat(u, c)], [f(x, u) + c * perturbation(x, u)])
    step = rk4_step(fc, plan.dt, plan.substeps)
    uc = ca.vertcat(u, c)
    x_next = step(x, uc)
    jac = ca.Function("step_sens", [x, uc], [ca.jacobian(x_next, x), ca.jacobian(x_next, c)])
    N = len(plan.u)
    A, C = jac.map(N)(plan.x[:-1].T, np.vstack([plan.u.T, np.zeros((1, N))]))
    A = np.array(A).reshape(n, N, n).transpose(1, 0, 2)
    C = np.array(C).reshape(n, N)
    dx = np.zeros(n)
    for k in range(N):
        dx = A[k] @ dx + C[:, k]
    return dx
