"""Noise levels of a state-space model: checked covariance matrices from what users write.

A noise level is given as one standard deviation per channel (``(n,)``, a diagonal
covariance), one number for every channel, or a full covariance matrix ``(n, n)``. Process
noise ``Q`` may be singular (a kinematic equation ``x1' = x2`` has none); measurement noise
``R`` must be positive definite, since a sensor without noise makes the innovation
covariance singular once its state is known.
"""
from __future__ import annotations

import numpy as np

from ..data.validation import as_float_array
from ..errors import DataError, ShapeError

#: relative asymmetry tolerated in a covariance matrix (rounding of user arithmetic)
SYMMETRY_TOLERANCE = 1e-9


def covariance(name: str, value, size: int, *, definite: bool, unit: str = "") -> np.ndarray:
    """``(size, size)`` covariance from a std (number or ``(size,)``) or a covariance.

    ``definite``: positive definite required (else semidefinite). ``unit`` is added to
    messages (``"per second"``). Raises ShapeError for a wrong size and DataError for a
    negative std, a non-symmetric matrix or a negative (or, with ``definite``, zero)
    eigenvalue."""
    arr = as_float_array(name, value)
    where = f" ({unit})" if unit else ""
    if not np.all(np.isfinite(arr)):
        raise DataError(f"{name} must be finite; got {arr.ravel()[:6]}")
    if arr.ndim == 0 or arr.shape == (size,):
        std = np.broadcast_to(arr, (size,))
        bad = std <= 0 if definite else std < 0
        if bad.any():
            rule = "positive" if definite else "non-negative"
            hint = (" (a sensor without noise makes the innovation covariance singular: give "
                    "a small std)" if definite else "")
            raise DataError(f"{name} must be {rule} standard deviations{where}; got "
                            f"{std.tolist()}{hint}")
        return np.diag(std ** 2)
    if arr.shape != (size, size):
        raise ShapeError(f"{name} must be a number, {size} standard deviations ({size},) or a "
                         f"covariance ({size}, {size}){where}; got shape {arr.shape}")
    scale = max(float(np.max(np.abs(arr))), 1e-300)
    if np.max(np.abs(arr - arr.T)) > SYMMETRY_TOLERANCE * scale:
        raise DataError(f"{name} must be a symmetric covariance matrix; it differs from its "
                        f"transpose by {np.max(np.abs(arr - arr.T)):.3g}")
    arr = (arr + arr.T) / 2
    smallest = float(np.linalg.eigvalsh(arr).min())
    if smallest < -SYMMETRY_TOLERANCE * scale or (definite and smallest <= 0):
        rule = "positive definite" if definite else "positive semidefinite"
        raise DataError(f"{name} must be {rule}; its smallest eigenvalue is {smallest:.3g}")
    return arr


def initial_covariance(P0, size: int) -> np.ndarray:
    """The initial state covariance ``P0`` (std or covariance, semidefinite allowed)."""
    return covariance("P0", P0, size, definite=False)
