"""Non-negative least squares of energy curves under soundness constraints, on Gram systems.

``dH ~ c + F xi`` with ``xi >= 0`` and ``rows @ xi <= bounds`` (:mod:`.soundness`). Every fit
is reduced once to its ``p x p`` statistics (``F^T F``, ``F^T dH`` after removing the means,
or the same of the per-block losses), so a support costs a ``k x k`` solve, not a pass over
the samples. The constrained problem is solved as Lawson and Hanson's least distance
programme (LSI -> LDP -> NNLS, *Solving Least Squares Problems*, ch. 23) with scipy's
``nnls``; written here because scipy has no least squares with general linear
inequalities.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import nnls

from ..optimizers.gram import residual_sum

#: ridge (relative to the equilibrated Gram's unit diagonal) when Cholesky fails
RIDGE = 1e-12


def _factor(gram: np.ndarray) -> np.ndarray:
    """Upper Cholesky factor ``R`` (``R^T R = gram``), with the smallest ridge that works.
    (numpy, not scipy.linalg: on a busy machine scipy's threaded BLAS took milliseconds
    per 4 x 4 triangular solve, numpy microseconds.)"""
    ridge = 0.0
    for _ in range(8):
        try:
            return np.linalg.cholesky(gram + ridge * np.eye(len(gram))).T
        except np.linalg.LinAlgError:
            ridge = RIDGE if ridge == 0 else ridge * 100
    return np.diag(np.sqrt(np.maximum(np.diag(gram), 1e-300)))


def solve_constrained(gram: np.ndarray, rhs: np.ndarray, rows: np.ndarray | None = None,
                      bounds: np.ndarray | None = None) -> np.ndarray:
    """``argmin xi^T G xi / 2 - rhs^T xi`` with ``xi >= 0`` and ``rows @ xi <= bounds``
    (``bounds >= 0``, so ``xi = 0`` is feasible). ``(k,)``."""
    k = len(rhs)
    if k == 0:
        return np.zeros(0)
    scale = np.sqrt(np.maximum(np.diag(gram), 1e-300))
    factor = _factor(gram / np.outer(scale, scale))
    inverse = np.linalg.inv(factor)                          # R^-1, k x k
    z = inverse.T @ (rhs / scale)                            # R^-T rhs
    xi = nnls(factor, z, maxiter=50 * k)[0]
    if rows is None or len(rows) == 0:
        return xi / scale
    scaled_rows = rows / scale
    if np.all(scaled_rows @ xi <= bounds * (1 + 1e-12)):
        return xi / scale
    # LSI -> LDP: xi = R^-1 (u + z); constraints E xi >= f become (E R^-1) u >= f - E R^-1 z
    e_r = np.vstack([inverse, -scaled_rows @ inverse])
    f = np.r_[np.zeros(k), -np.asarray(bounds, float)]
    f_t = f - e_r @ z
    norm = max(float(np.max(np.abs(e_r))), 1e-300)
    a = np.vstack([e_r.T / norm, f_t / norm])
    target = np.r_[np.zeros(k), 1.0]
    w = nnls(a, target, maxiter=50 * (k + len(f)))[0]
    r = a @ w - target
    if abs(r[k]) < 1e-14:      # numerically infeasible: no term at all is always sound
        return np.zeros(k)
    xi = np.maximum(inverse @ (-r[:k] / r[k] + z), 0.0)
    worst = float(np.max(scaled_rows @ xi / np.maximum(bounds, 1e-300), initial=0.0))
    if worst > 1:              # rounding: shrinking keeps every constraint (rows >= 0)
        xi = xi / worst
    return _polish(xi, factor.T @ factor, rhs / scale, scaled_rows, bounds) / scale


def _polish(xi, gram, rhs, rows, bounds) -> np.ndarray:
    """The LDP solution is accurate to ~1e-8 and leaves ~1e-14 where a coefficient is 0:
    solve the KKT system of its active set exactly (zeros exact, active constraints as
    equalities) and keep that when it is feasible and no worse."""
    free = xi > 1e-9 * max(float(np.max(xi)), 1e-300)
    active = rows @ xi >= bounds * (1 - 1e-7)
    if not np.any(free):
        return np.zeros_like(xi)
    a = rows[np.ix_(active, free)]
    n, c = int(free.sum()), int(active.sum())
    kkt = np.block([[gram[np.ix_(free, free)], a.T], [a, np.zeros((c, c))]])
    solution = np.linalg.lstsq(kkt, np.r_[rhs[free], bounds[active]], rcond=None)[0]
    polished = np.zeros_like(xi)
    polished[free] = solution[:n]
    objective = lambda v: 0.5 * v @ gram @ v - rhs @ v    # noqa: E731
    feasible = np.all(polished >= 0) and np.all(rows @ polished <= bounds * (1 + 1e-12))
    return polished if feasible and objective(polished) <= objective(xi) else \
        np.where(free, xi, 0.0)


@dataclass(frozen=True)
class Statistics:
    """One least-squares problem ``y ~ c + D xi`` reduced to its statistics.

    ``gram = D~^T D~``, ``rhs = D~^T y~``, ``yy = y~^T y~`` with ``D~, y~`` the (weighted)
    design and target after their means; ``mean_y``, ``mean_f`` give the offset
    ``c = mean_y - mean_f @ xi`` over the fitted samples."""

    gram: np.ndarray
    rhs: np.ndarray
    yy: float
    mean_y: float
    mean_f: np.ndarray

    def fit(self, subset, rows=None, bounds=None) -> tuple[np.ndarray, float]:
        """Coefficients ``(k,)`` of the terms ``subset`` and the loss."""
        s = list(subset)
        gram, rhs = self.gram[np.ix_(s, s)], self.rhs[s]      # one copy for both (read only)
        xi = solve_constrained(gram, rhs, rows, bounds)
        loss = residual_sum(gram, rhs, self.yy, xi)
        return xi, float(loss)

    def offset(self, subset, xi) -> float:
        """The intercept ``c = mean_y - mean_f @ xi`` for coefficients ``xi`` ``(k,)`` of the
        terms ``subset``, in the target's units."""
        return float(self.mean_y - self.mean_f[list(subset)] @ xi)

    def restricted(self, columns, *, shift_y: float = 0.0, shift_f=0.0) -> Statistics:
        """The statistics of the columns ``columns`` only, with the target and features
        shifted by constants (``y - shift_y``, ``F - shift_f``: a window's restart), which
        change only the means."""
        c = list(columns)
        return Statistics(self.gram[np.ix_(c, c)], self.rhs[c], self.yy, self.mean_y - shift_y,
                          self.mean_f[c] - shift_f)


def cumulative_statistics(features: np.ndarray, target: np.ndarray) -> Statistics:
    """Least squares on the cumulative curves ``target ~ c + features @ xi``."""
    mean_f, mean_y = features.mean(axis=0), float(target.mean())
    d, y = features - mean_f, target - mean_y
    return Statistics(d.T @ d, d.T @ y, float(y @ y), mean_y, mean_f)


def block_means(values: np.ndarray, block: int) -> np.ndarray:
    """Means over consecutive blocks of ``block`` samples (a last partial block is dropped):
    ``(m, ...)`` -> ``(m // block, ...)``."""
    n = len(values) // block
    return values[:n * block].reshape(n, block, *values.shape[1:]).mean(axis=1)


def block_weights(target: np.ndarray, block: int) -> np.ndarray:
    """Relative weights ``1 / |energy lost per block|`` of the block fit."""
    loss = np.diff(block_means(target, block))
    return 1.0 / np.maximum(np.abs(loss), 1e-3 * np.max(np.abs(loss)))


def block_statistics(features: np.ndarray, target: np.ndarray, block: int,
                     weights: np.ndarray | None = None) -> Statistics:
    """The energy lost from one block of ``block`` samples to the next, fitted with
    *relative* weights ``1 / loss`` (or the given ``weights``): late, low-energy blocks count
    as much as early ones. The loss is taken between the blocks' mean levels, not between
    single samples at their edges, whose pointwise noise of ``H_m`` picked wrong laws on
    simulated encoder data. The offset is the mean residual over all samples."""
    loss = np.diff(block_means(target, block))
    gained = np.diff(block_means(features, block), axis=0)
    w = block_weights(target, block) if weights is None else weights
    d, y = gained * w[:, None], loss * w
    return Statistics(d.T @ d, d.T @ y, float(y @ y), float(target.mean()),
                      features.mean(axis=0))


def statistics(features, target, block=None, weights=None) -> Statistics:
    """Cumulative (``block=None``) or per-block statistics."""
    if block is None:
        return cumulative_statistics(features, target)
    return block_statistics(features, target, block, weights)


def nonnegative_fit(features: np.ndarray, target: np.ndarray, block: int | None = None,
                    weights: np.ndarray | None = None, limits=None) -> np.ndarray:
    """``[c, xi]`` of ``target ~ c + features @ xi`` with ``xi >= 0`` and, when ``limits``
    (a :class:`~discrepancy.energy.soundness.Limits` of these columns) is given,
    ``limits.rows @ xi <= limits.bounds``. ``block``: see :func:`block_statistics`."""
    stats = statistics(features, target, block, weights)
    columns = range(features.shape[1])
    rows, bounds = (None, None) if limits is None else (limits.rows, limits.bounds)
    xi, _ = stats.fit(columns, rows, bounds)
    return np.r_[stats.offset(columns, xi), xi]
