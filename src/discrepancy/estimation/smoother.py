"""The Rauch–Tung–Striebel smoother: every state estimated from the whole record.

Run backwards over a :class:`~discrepancy.estimation.FilterResult`: with the filtered
belief ``(x_i, P_i)``, the next prediction ``(x⁻_{i+1}, P⁻_{i+1})`` and their covariance
``C_i = Cov(x_i, x⁻_{i+1})`` (``P_i Φᵀ`` for the EKF, the sigma points' cross-covariance for
the UKF), the gain ``G = C_i (P⁻_{i+1})⁻¹`` carries the smoothed correction back:
``xs_i = x_i + G (xs_{i+1} - x⁻_{i+1})``, ``Ps_i = P_i + G (Ps_{i+1} - P⁻_{i+1}) Gᵀ``. Written
here (a few lines of numpy per sample); the filters give every term it needs.
"""
from __future__ import annotations

import numpy as np
import scipy.linalg

from ..errors import ParameterError
from .results import FilterResult


def rts_smooth(result: FilterResult) -> tuple[np.ndarray, np.ndarray]:
    """Smoothed means ``(m, n)`` and covariances ``(m, n, n)``."""
    if not isinstance(result, FilterResult):
        raise ParameterError(f"smooth takes the FilterResult of filter(...); got "
                             f"{type(result).__name__}")
    xs, Ps = result.x.copy(), result.P.copy()
    for i in range(len(xs) - 2, -1, -1):
        gain = _gain(result.cross[i], result.P_predicted[i + 1])
        xs[i] = result.x[i] + gain @ (xs[i + 1] - result.x_predicted[i + 1])
        Ps[i] = result.P[i] + gain @ (Ps[i + 1] - result.P_predicted[i + 1]) @ gain.T
        Ps[i] = (Ps[i] + Ps[i].T) / 2
    return xs, Ps


def _gain(cross: np.ndarray, predicted: np.ndarray) -> np.ndarray:
    """``C P⁻¹`` (least squares when ``P`` is singular: a state known exactly)."""
    try:
        return scipy.linalg.solve(predicted, cross.T, assume_a="pos").T
    except (np.linalg.LinAlgError, ValueError):
        return np.linalg.lstsq(predicted, cross.T, rcond=None)[0].T
