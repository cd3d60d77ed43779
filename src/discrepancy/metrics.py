"""Standard figures of merit of system identification, for outputs ``(m,)`` or ``(m, k)``.

* :func:`rms_error`: root-mean-square error, in the outputs' units (per output column);
* :func:`nrmse`: RMS error over the measured output's standard deviation;
* :func:`fit_percent`: ``100 (1 - |y - ŷ| / |y - mean(y)|)`` (MATLAB's ``compare``);
  100 is perfect, 0 is no better than the mean.
"""
from __future__ import annotations

import numpy as np

from .data.validation import check_array
from .errors import DataError, ShapeError


def _pair(measured, predicted):
    y = check_array("measured", measured, allow_1d=True)
    y_hat = check_array("predicted", predicted, allow_1d=True)
    if y.shape != y_hat.shape:
        raise ShapeError(f"measured and predicted must have the same shape; got {y.shape} "
                         f"and {y_hat.shape}")
    if y.shape[0] == 0:
        raise DataError("measured and predicted must hold at least one sample; got none")
    return y, y_hat


def _spread(size, what: str) -> np.ndarray:
    """``size`` ``(k,)`` of each measured column, refused where it is zero (a constant
    signal: the normalised figure is undefined, not huge)."""
    flat = np.flatnonzero(size == 0)
    if flat.size:
        raise DataError(f"measured column(s) {flat.tolist()} are constant, so {what} (which "
                        "divides by the measured signal's spread) is undefined; use "
                        "rms_error")
    return size


def rms_error(measured, predicted) -> np.ndarray | float:
    """RMS of ``predicted - measured`` per column (a float for one column)."""
    y, y_hat = _pair(measured, predicted)
    out = np.sqrt(np.mean((y_hat - y) ** 2, axis=0))
    return float(out[0]) if out.size == 1 else out


def nrmse(measured, predicted) -> np.ndarray | float:
    """RMS error over the standard deviation of ``measured``, per column."""
    y, y_hat = _pair(measured, predicted)
    out = np.sqrt(np.mean((y_hat - y) ** 2, axis=0)) / _spread(y.std(axis=0), "nrmse")
    return float(out[0]) if out.size == 1 else out


def fit_percent(measured, predicted) -> np.ndarray | float:
    """``100 (1 - |y - ŷ| / |y - mean(y)|)`` per column."""
    y, y_hat = _pair(measured, predicted)
    spread = _spread(np.linalg.norm(y - y.mean(axis=0), axis=0), "fit_percent")
    out = 100 * (1 - np.linalg.norm(y - y_hat, axis=0) / spread)
    return float(out[0]) if out.size == 1 else out
