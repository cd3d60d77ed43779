"""The filters' formulas, written once for both arithmetics of
:mod:`~discrepancy.estimation.backends` (numpy arrays or CasADi symbols, as ``ops``).

Prediction over one sample interval of a continuous-time model integrates, with the same
RK4 steps (and inputs at the same stage times) as ``simulate(method="rk4")``, the state,
its Jacobian ``Φ`` (the variational equation ``Φ' = A Φ``, which the same Runge–Kutta
steps turn into the exact Jacobian of the discrete map) and the process noise
``Γ = ∫ Φ(t, s) Q Φ(t, s)ᵀ ds`` (``Γ' = A Γ + Γ Aᵀ + Q``, ``Q`` per second), so on a
linear model the prediction is the exact discretisation (``e^{Ah}``, Van Loan's noise) to
RK4's accuracy. A discrete-time model's map gives ``Φ`` directly and ``Γ = Q`` (per step).

Updates take a mask ``w`` (1 for each output measured at this sample, 0 for a missing
one): the missing rows get a unit innovation variance and a zero innovation, so they
change nothing and add nothing to the likelihood, without branches (the CasADi form is
one Function for every pattern of missing samples).
"""
from __future__ import annotations

import numpy as np

from ..runge_kutta import runge_kutta_step

LOG_2PI = float(np.log(2 * np.pi))


def rk4(ops, rates, z, stages, h, substeps: int):
    """``substeps`` RK4 steps of ``z' = rates(z, u)`` (``z`` a tuple) over ``h``, the input
    at the stage times (rows ``2s``, ``2s + 1``, ``2s + 2`` of ``stages`` for substep
    ``s``)."""
    dt, z = h / substeps, _Parts(z)

    def parts_rates(parts, u):
        return _Parts(rates(parts, u))

    for s in range(substeps):
        u0, um, u1 = (ops.stage(stages, 2 * s + j) for j in range(3))
        z = runge_kutta_step(parts_rates, z, dt, u0, um, u1)
    return tuple(z)


class _Parts(tuple):
    """Arrays moved together by one RK4 step (a state, its Jacobian, its noise): added
    part by part and scaled by a step length, numpy arrays and CasADi symbols alike."""

    __array_ufunc__ = None    # ``numpy scalar * parts`` scales the parts (``__rmul__``)

    def __add__(self, other):
        return _Parts(a + b for a, b in zip(self, other, strict=True))

    def __mul__(self, factor):
        return _Parts(factor * a for a in self)

    __rmul__ = __mul__


def propagate(ops, x, stages, h, Q, substeps: int, discrete: bool):
    """``(x_next, Φ, Γ)`` over one interval (see the module's docstring)."""
    if discrete:
        value, jac = ops.f_and_jac(x, ops.stage(stages, 0))
        return value, jac, Q
    n = Q.shape[0]

    def rates(z, u):
        state, phi, gamma = z
        value, A = ops.f_and_jac(state, u)
        return value, A @ phi, A @ gamma + gamma @ A.T + Q

    return rk4(ops, rates, (x, ops.eye(n), ops.zeros(n, n)), stages, h, substeps)


def propagate_columns(ops, X, stages, h, substeps: int, discrete: bool):
    """Every column of ``X`` (sigma points) moved over one interval."""
    if discrete:
        return ops.f_columns(X, ops.stage(stages, 0))
    return rk4(ops, lambda z, u: (ops.f_columns(z[0], u),), (X,), stages, h, substeps)[0]


def ekf_predict(ops, x, P, stages, h, Q, substeps: int, discrete: bool):
    """Predicted mean and covariance, and ``C = Cov(x_k, x_{k+1})`` (for smoothing)."""
    x_next, phi, gamma = propagate(ops, x, stages, h, Q, substeps, discrete)
    cross = P @ phi.T
    return x_next, ops.sym(phi @ cross + gamma), cross


def masked_update(ops, x, P, e, S_full, cross, w, joseph=None):
    """The update of ``x``, ``P`` from the innovation ``e``, its covariance ``S_full`` and
    ``Cov(x, y)`` (all outputs), keeping the rows the mask ``w`` measures. ``joseph``:
    ``(H, R)`` for the Joseph form (linearised updates; ``P`` stays positive
    semidefinite), else ``P - K S Kᵀ``. Returns ``(x, P, e, S, nll)``."""
    k = S_full.shape[0]
    W = ops.diag(w)
    e = W @ e
    S = W @ S_full @ W + ops.eye(k) - W
    L = ops.chol(S)
    gain = ops.cho_solve(L, (cross @ W).T).T          # zero columns where nothing measured
    if joseph is None:
        P_new = P - gain @ S @ gain.T
    else:
        H, R = joseph
        A = ops.eye(P.shape[0]) - gain @ H
        P_new = A @ P @ A.T + gain @ R @ gain.T
    nll = 0.5 * (ops.dot(e, ops.cho_solve(L, e)) + ops.logdet(L) + LOG_2PI * ops.total(w))
    return x + gain @ e, ops.sym(P_new), e, S, nll


def ekf_update(ops, x, P, y, w, R):
    """Linearised update with the measurement ``y`` (zeros where ``w`` is 0)."""
    H = ops.h_jac(x)
    cross = P @ H.T
    return masked_update(ops, x, P, y - ops.h(x), H @ cross + R, cross, w, joseph=(H, R))


# ------------------------------------------------------------------- unscented
def unscented_weights(n: int, alpha: float, beta: float, kappa: float):
    """``(scale, Wm, Wc)``: sigma points at ``x ± scale · columns of √P``."""
    lam = alpha ** 2 * (n + kappa) - n
    wm = np.full(2 * n + 1, 1 / (2 * (n + lam)))
    wc = wm.copy()
    wm[0] = lam / (n + lam)
    wc[0] = wm[0] + 1 - alpha ** 2 + beta
    return float(np.sqrt(n + lam)), wm, wc


def sigma_points(ops, x, P, scale):
    """The ``2n + 1`` sigma points as columns ``(n, 2n + 1)``: ``x``, then ``x + scale ·``
    each column of a square root of ``P``, then ``x - scale ·`` each."""
    root = scale * ops.psd_sqrt(P)
    n = P.shape[0]
    return ops.columns([x, *(x + ops.column(root, j) for j in range(n)),
                        *(x - ops.column(root, j) for j in range(n))])


def ukf_predict(ops, x, P, stages, h, Q, substeps: int, discrete: bool, weights):
    """Unscented prediction; the process noise ``Γ`` integrated along the mean's path as in
    :func:`ekf_predict` (so the two filters agree exactly on linear models)."""
    scale, wm, wc = weights
    X = sigma_points(ops, x, P, scale)
    moved = propagate_columns(ops, X, stages, h, substeps, discrete)
    gamma = propagate(ops, x, stages, h, Q, substeps, discrete)[2]
    mean = moved @ wm
    spread = ops.center(moved, mean)
    weighted = spread @ ops.diag(wc)
    cross = ops.center(X, x) @ ops.diag(wc) @ spread.T
    return mean, ops.sym(weighted @ spread.T + gamma), cross


def ukf_update(ops, x, P, y, w, R, weights):
    """Unscented update with the measurement ``y`` (zeros where ``w`` is 0): the outputs of
    the sigma points give the innovation's mean, covariance (plus ``R``) and ``Cov(x, y)``;
    returns ``(x, P, e, S, nll)`` as :func:`masked_update`."""
    scale, wm, wc = weights
    X = sigma_points(ops, x, P, scale)
    Y = ops.h_columns(X)
    y_mean = Y @ wm
    spread = ops.center(Y, y_mean)
    S_full = spread @ ops.diag(wc) @ spread.T + R
    cross = ops.center(X, x) @ ops.diag(wc) @ spread.T
    return masked_update(ops, x, P, y - y_mean, S_full, cross, w)
