"""State estimation over any hybrid model: extended and unscented Kalman filters, the
Rauch–Tung–Striebel smoother, and prediction-error fits of the discrepancy.

Importing this package needs no optional dependency; with CasADi (``[control]``) the
filters run compiled with exact Jacobians (see :mod:`discrepancy.estimation.filters`).
"""
from .filters import ExtendedKalmanFilter, KalmanFilter, UnscentedKalmanFilter
from .results import FilterResult, FilterState

__all__ = ["ExtendedKalmanFilter", "FilterResult", "FilterState", "KalmanFilter",
           "UnscentedKalmanFilter"]
