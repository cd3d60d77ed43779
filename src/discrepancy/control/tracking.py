"""Time-varying LQR tracking of a plan on the planning model's linearisation.

The plan's own discrete step (``substeps`` RK4 steps with the input held) is
linearised about the planned states and inputs, ``dx[k+1] = A_k dx[k] + B_k du[k]``,
and the finite-horizon discrete Riccati recursion gives gains ``K_k``. The
controller is sampled at the grid times: ``u_k = u_plan[k] - K_k (x(t_k) - x_plan[k])``.
After the plan it balances about the plan's final state with the stationary LQR gain
there (the discrete algebraic Riccati equation of the same step).
"""
from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np
from scipy.linalg import solve_discrete_are

from ..data.validation import as_float_array, check_vector
from ..errors import InfeasibleError, ParameterError, ShapeError, describe
from .dynamics import as_casadi, rk4_step
from .trajectory import Plan, check_plan


@dataclass(frozen=True)
class Tracker:
    """Sampled-data tracking law ``law(k, x) -> u (r,)`` for :func:`~.replay.replay`.

    Attributes:
        plan: the tracked plan; gains: ``(N, r, n)``; u_bounds: ``(r, 2)`` saturation or None.
        cost_to_go: ``(N+1, n, n)`` Riccati matrices ``P_k`` (``x'P_k x``: the LQR cost from
            step ``k`` on); final_gain: ``(r, n)`` stationary gain about the plan's end,
            used for ``k >= N``; u_final: ``(r,)`` input held there (default 0).
    """

    plan: Plan
    gains: np.ndarray
    u_bounds: np.ndarray | None = None
    cost_to_go: np.ndarray | None = None
    final_gain: np.ndarray | None = None
    u_final: np.ndarray | None = None

    def __post_init__(self):
        check_plan(self.plan)
        expected = (len(self.plan.u), self.plan.u.shape[1], self.plan.x.shape[1])
        if np.shape(self.gains) != expected:
            raise ShapeError(f"gains must be (N, r, n) = {expected} for this plan; got "
                             f"{describe(self.gains)}")

    def __call__(self, k: int, x: np.ndarray) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        if k < len(self.gains):
            u = self.plan.u[k] - self.gains[k] @ (x - self.plan.x[k])
        else:  # after the plan: balance about its final state
            gain = self.gains[-1] if self.final_gain is None else self.final_gain
            u0 = np.zeros(self.gains.shape[1]) if self.u_final is None else self.u_final
            u = u0 - gain @ (x - self.plan.x[-1])
        if self.u_bounds is not None:
            u = np.clip(u, self.u_bounds[:, 0], self.u_bounds[:, 1])
        return u


def weight_matrix(name, w, size):
    """A weight as a ``(size, size)`` matrix: finite, symmetric and positive semidefinite
    (a negative weight would reward the error it should penalise), checked by name."""
    try:
        w = np.atleast_1d(np.asarray(w, dtype=float))
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be a number, ({size},) diagonal weights or a "
                             f"({size}, {size}) matrix; got {describe(w)}") from None
    if w.ndim == 1 and w.shape[0] in (1, size):
        w = np.diag(np.broadcast_to(w, (size,)))
    elif w.shape != (size, size):
        raise ShapeError(f"{name} must be a scalar, ({size},) diagonal or ({size}, {size}); "
                         f"got shape {w.shape}")
    if not np.all(np.isfinite(w)):
        raise ParameterError(f"{name} must be finite weights; got {w.tolist()}")
    if not np.allclose(w, w.T, rtol=1e-10, atol=0):
        raise ParameterError(f"{name} must be a symmetric matrix; got {w.tolist()}")
    lowest = float(np.linalg.eigvalsh(w).min())
    if lowest < -1e-12 * max(1.0, float(np.abs(w).max())):
        negative = [i for i in range(size) if w[i, i] < 0]
        where = f"diagonal entries {negative} are negative" if negative else \
            f"its smallest eigenvalue is {lowest:.3g}"
        raise ParameterError(f"{name} must be positive semidefinite weights (>= 0); {where}: "
                             f"{w.tolist() if size <= 6 else '...'}")
    return w


def step_jacobians(model, dt: float, substeps: int) -> ca.Function:
    """CasADi ``(x, u) -> (A, B)``: Jacobians of the held-input RK4 step of ``model``."""
    f = as_casadi(model)
    n, r = f.size1_in(0), f.size1_in(1)
    step = rk4_step(f, dt, substeps)
    x, u = ca.SX.sym("x", n), ca.SX.sym("u", r)
    x_next = step(x, u)
    return ca.Function("step_jacobians", [x, u], [ca.jacobian(x_next, x),
                                                  ca.jacobian(x_next, u)])


def linearise(model, plan: Plan):
    """``A (N, n, n)``, ``B (N, n, r)``: Jacobians of the plan's discrete step along the plan."""
    check_plan(plan)
    jac = step_jacobians(model, plan.dt, plan.substeps)
    n, r = plan.x.shape[1], plan.u.shape[1]
    N = len(plan.u)
    A, B = jac.map(N)(plan.x[:-1].T, plan.u.T)
    A = np.array(A).reshape(n, N, n).transpose(1, 0, 2)
    B = np.array(B).reshape(n, N, r).transpose(1, 0, 2)
    return A, B


def stationary_lqr(model, x_eq, u_eq, *, dt: float, substeps: int, Q, R):
    """``(K (r, n), P (n, n))``: infinite-horizon discrete LQR about ``(x_eq, u_eq)`` for the
    held-input step of ``model``; ``(None, None)`` if the Riccati equation has no
    stabilising solution there (e.g. not an equilibrium one can stabilise). ``Q``, ``R``:
    weights as :class:`~.mpc.MPC` takes them (numbers, diagonals or matrices, >= 0)."""
    jacobians = step_jacobians(model, dt, substeps)
    x_eq = check_vector("x_eq", x_eq, jacobians.size1_in(0))
    u_eq = check_vector("u_eq", u_eq, jacobians.size1_in(1))
    A, B = (np.array(m) for m in jacobians(x_eq, u_eq))
    Q, R = weight_matrix("Q", Q, A.shape[0]), weight_matrix("R", R, B.shape[1])
    try:
        P = solve_discrete_are(A, B, Q, R)
    except (np.linalg.LinAlgError, ValueError):
        return None, None
    return np.linalg.solve(R + B.T @ P @ B, B.T @ P @ A), P


def tvlqr(model, plan: Plan, *, Q=None, R=1.0, Q_final=None, u_bounds=None,
          u_final=None) -> Tracker:
    """Finite-horizon discrete LQR along ``plan`` on ``model`` (the planning model).

    Args:
        model: the model the plan was made on (anything :func:`as_casadi` accepts).
        plan: the :class:`~.trajectory.Plan` to track.
        Q, R: stage weights on state / input deviations (diagonal entries or matrices);
            default identity and 1 (the paper's swing-up weights are ``PAPER_Q``, ``PAPER_R``).
        Q_final: terminal weight; ``100 Q`` by default, to arrive close to the plan's end;
            ``"lqr"``: the stationary Riccati solution about the plan's end (so the tracker
            hands over smoothly to balancing there).
        u_bounds: optional ``(r, 2)`` input saturation applied by the tracker.
        u_final: ``(r,)`` input that holds the plan's final state (default 0), about which
            the tracker balances after the plan.
    """
    A, B = linearise(model, plan)
    n, r = A.shape[1], B.shape[2]
    Qm, Rm = weight_matrix("Q", np.ones(n) if Q is None else Q, n), weight_matrix("R", R, r)
    uf = np.zeros(r) if u_final is None else np.asarray(u_final, dtype=float).reshape(r)
    K_inf, P_inf = stationary_lqr(model, plan.x[-1], uf, dt=plan.dt, substeps=plan.substeps,
                                  Q=Qm, R=Rm)
    if isinstance(Q_final, str):
        if Q_final != "lqr":
            raise ParameterError(f"Q_final must be weights or 'lqr'; got {Q_final!r}")
        if P_inf is None:
            raise InfeasibleError("Q_final='lqr' needs a stabilisable equilibrium at the "
                                  "plan's end; the Riccati equation there has no stabilising "
                                  "solution")
        P = P_inf
    else:
        P = 100.0 * Qm if Q_final is None else weight_matrix("Q_final", Q_final, n)
    gains = np.zeros((len(A), r, n))
    costs = np.zeros((len(A) + 1, n, n))
    costs[-1] = P
    for k in range(len(A) - 1, -1, -1):
        a, b = A[k], B[k]
        K = np.linalg.solve(Rm + b.T @ P @ b, b.T @ P @ a)
        P = Qm + a.T @ P @ (a - b @ K)
        P = (P + P.T) / 2
        gains[k], costs[k] = K, P
    bounds = None if u_bounds is None else as_float_array("u_bounds", u_bounds)
    if bounds is not None and (bounds.size != 2 * r or np.isnan(bounds).any()
                               or np.any(bounds.reshape(r, 2)[:, 0] > bounds.reshape(r, 2)[:, 1])):
        raise ShapeError(f"u_bounds must be ({r}, 2) rows of (lower, upper) with lower <= upper; "
                         f"got {describe(u_bounds)}")
    bounds = None if bounds is None else bounds.reshape(r, 2)
    return Tracker(plan=plan, gains=gains, u_bounds=bounds, cost_to_go=costs,
                   final_gain=K_inf, u_final=uf)
