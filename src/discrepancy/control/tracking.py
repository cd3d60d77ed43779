"""Time-varying LQR tracking of a plan on the planning model's linearisation.

The plan's own discrete step (``substeps`` RK4 steps with the input held) is
linearised about the planned states and inputs, ``dx[k+1] = A_k dx[k] + B_k du[k]``,
and the finite-horizon discrete Riccati recursion gives gains ``K_k``. The
controller is sampled at the grid times: ``u_k = u_plan[k] - K_k (x(t_k) - x_plan[k])``.
"""
from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..errors import ShapeError
from .dynamics import as_casadi, rk4_step
from .trajectory import Plan


@dataclass(frozen=True)
class Tracker:
    """Sampled-data tracking law ``law(k, x) -> u (r,)`` for :func:`~.replay.replay`.

    Attributes:
        plan: the tracked plan; gains: ``(N, r, n)``; u_bounds: ``(r, 2)`` saturation or None.
    """

    plan: Plan
    gains: np.ndarray
    u_bounds: np.ndarray | None = None

    def __call__(self, k: int, x: np.ndarray) -> np.ndarray:
        u = self.plan.u[k] - self.gains[k] @ (np.asarray(x, dtype=float) - self.plan.x[k])
        if self.u_bounds is not None:
            u = np.clip(u, self.u_bounds[:, 0], self.u_bounds[:, 1])
        return u


def _diag(name, w, size):
    w = np.atleast_1d(np.asarray(w, dtype=float))
    if w.ndim == 1 and w.shape[0] in (1, size):
        return np.diag(np.broadcast_to(w, (size,)))
    if w.shape == (size, size):
        return w
    raise ShapeError(f"{name} must be a scalar, ({size},) diagonal or ({size}, {size}); got "
                     f"shape {w.shape}")


def linearise(model, plan: Plan):
    """``A (N, n, n)``, ``B (N, n, r)``: Jacobians of the plan's discrete step along the plan."""
    f = as_casadi(model)
    n, r = f.size1_in(0), f.size1_in(1)
    step = rk4_step(f, plan.dt, plan.substeps)
    x, u = ca.SX.sym("x", n), ca.SX.sym("u", r)
    x_next = step(x, u)
    jac = ca.Function("step_jacobians", [x, u], [ca.jacobian(x_next, x), ca.jacobian(x_next, u)])
    N = len(plan.u)
    A, B = jac.map(N)(plan.x[:-1].T, plan.u.T)
    A = np.array(A).reshape(n, N, n).transpose(1, 0, 2)
    B = np.array(B).reshape(n, N, r).transpose(1, 0, 2)
    return A, B


def tvlqr(model, plan: Plan, *, Q=None, R=1.0, Q_final=None,
          u_bounds=None) -> Tracker:
    """Finite-horizon discrete LQR along ``plan`` on ``model`` (the planning model).

    Args:
        model: the model the plan was made on (anything :func:`as_casadi` accepts).
        plan: the :class:`~.trajectory.Plan` to track.
        Q, R: stage weights on state / input deviations (diagonal entries or matrices);
            default identity and 1 (the paper's swing-up weights are ``PAPER_Q``, ``PAPER_R``).
        Q_final: terminal weight; ``100 Q`` by default, to arrive close to the plan's end.
        u_bounds: optional ``(r, 2)`` input saturation applied by the tracker.
    """
    A, B = linearise(model, plan)
    n, r = A.shape[1], B.shape[2]
    Qm, Rm = _diag("Q", np.ones(n) if Q is None else Q, n), _diag("R", R, r)
    P = 100.0 * Qm if Q_final is None else _diag("Q_final", Q_final, n)
    gains = np.zeros((len(A), r, n))
    for k in range(len(A) - 1, -1, -1):
        a, b = A[k], B[k]
        K = np.linalg.solve(Rm + b.T @ P @ b, b.T @ P @ a)
        P = Qm + a.T @ P @ (a - b @ K)
        P = (P + P.T) / 2
        gains[k] = K
    bounds = None if u_bounds is None else np.asarray(u_bounds, dtype=float).reshape(r, 2)
    return Tracker(plan=plan, gains=gains, u_bounds=bounds)
