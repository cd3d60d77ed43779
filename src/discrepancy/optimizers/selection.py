"""Choosing the STLSQ threshold from the data (no hand tuning).

Every candidate support's residual sum of squares follows from the Gram
statistics (``yᵀy − 2ξᵀΘᵀy + ξᵀΘᵀΘξ``), so the whole threshold path costs a few
p×p solves. For each target the threshold with the smallest Bayesian
information criterion ``m log(RSS/m) + k log m`` is kept.
"""
from __future__ import annotations

import warnings

import numpy as np

from .base import solve_normal


def candidate_thresholds(gram: np.ndarray, rhs_column: np.ndarray, alpha: float) -> np.ndarray:
    """Thresholds just above each coefficient magnitude of the full ridge solution (and 0)."""
    full = np.abs(solve_normal(gram, rhs_column, alpha))
    levels = np.unique(full[full > 0])
    return np.concatenate([[0.0], levels * (1 + 1e-9)])


def bic(rss: float, k: int, m: int) -> float:
    """Bayesian information criterion of a Gaussian model with k terms on m samples."""
    return m * np.log(max(rss, 1e-300) / m) + k * np.log(m)


def select_thresholds(stlsq, gram, rhs, yy, n_samples: int) -> tuple[np.ndarray, np.ndarray]:
    """Per target, the BIC-best STLSQ solution over the threshold path.

    Returns ``(coef (n, p), thresholds (n,))``.
    """
    from copy import copy

    p, n = rhs.shape
    coef, chosen = np.zeros((n, p)), np.zeros(n)
    for i in range(n):
        best = None
        for threshold in candidate_thresholds(gram, rhs[:, i], stlsq.alpha):
            solver = copy(stlsq)
            solver.threshold = float(threshold)
            with warnings.catch_warnings():  # an empty model is a legitimate candidate
                warnings.simplefilter("ignore")
                c = solver._solve_fixed(gram, rhs[:, i:i + 1])[0]
            rss = yy[i] - 2 * c @ rhs[:, i] + c @ gram @ c
            score = bic(rss, int(np.count_nonzero(c)), n_samples)
            if best is None or score < best[0] - 1e-9 * abs(best[0]):
                best = (score, c, threshold)
        coef[i], chosen[i] = best[1], best[2]
    return coef, chosen
