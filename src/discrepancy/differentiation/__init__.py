"""Numerical differentiation: one registry behind one interface."""
from .auto import AutoSmoothing
from .base import Differentiator, available_methods, get_differentiation_method
from .dequantise import Dequantised
from .finite_difference import FiniteDifference
from .methods import Kalman, SavitzkyGolay, Spline, TrendFiltered
from .spectral import Spectral
from .spline import SmoothingSpline
from .weak import WeakForm

__all__ = ["AutoSmoothing", "Dequantised", "Differentiator", "FiniteDifference", "Kalman",
           "SavitzkyGolay", "SmoothingSpline", "Spectral", "Spline", "TrendFiltered", "WeakForm",
           "available_methods", "get_differentiation_method"]
