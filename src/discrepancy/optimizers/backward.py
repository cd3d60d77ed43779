"""Backward elimination: a second path of candidate supports, robust to collinear columns.

STLSQ's threshold path orders terms by the size of their ridge coefficients; when columns
are strongly collinear (polynomials of a field with a large mean: ``1, u, u², u v`` with
``u ≈ 0.6 ± 0.3``), the ridge spreads a term over its neighbours and the true support may
never appear on that path. Backward elimination removes, one at a time, the term whose
removal raises the residual sum of squares least: ``ξ_j² / (G⁻¹)_jj`` for the least-squares
solution of the current support (a scale-free criterion). The inverse is downdated by one
rank-one step per removal and refreshed every :data:`REFRESH` steps, so the whole path of
``p`` supports costs about one ``p × p`` inversion. Candidates from both paths are then
scored by the same cross-validation
(:func:`~discrepancy.optimizers.selection.select_thresholds`, ``extra=``).
"""
from __future__ import annotations

import numpy as np

#: removals between recomputing the inverse from scratch (the rank-one downdates drift)
REFRESH = 16


def _inverse(gram: np.ndarray, index: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pseudo-inverse of the equilibrated sub-Gram, and the equilibration."""
    sub = gram[np.ix_(index, index)]
    d = np.sqrt(np.diag(sub))
    d[d == 0] = 1.0
    return np.linalg.pinv(sub / np.outer(d, d), hermitian=True), d


def backward_path(gram: np.ndarray, rhs: np.ndarray, allowed: np.ndarray | None = None
                  ) -> list[np.ndarray]:
    """Supports ``(p,)`` from all ``allowed`` terms down to one, each one term smaller."""
    current = np.ones(len(rhs), bool) if allowed is None else allowed.copy()
    out = []
    index = np.flatnonzero(current)
    inv, d = _inverse(gram, index)
    for step in range(len(index)):
        out.append(current.copy())
        if len(index) == 1:
            break
        coef = inv @ (rhs[index] / d)
        diagonal = np.maximum(np.diag(inv), 1e-300)
        k = int(np.argmin(coef ** 2 / diagonal))
        current[index[k]] = False
        keep = np.arange(len(index)) != k
        if (step + 1) % REFRESH == 0:
            index = index[keep]
            inv, d = _inverse(gram, index)
            continue
        inv = inv[np.ix_(keep, keep)] - np.outer(inv[keep, k], inv[k, keep]) / inv[k, k]
        index, d = index[keep], d[keep]
    return out
