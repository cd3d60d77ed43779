"""Numerical differentiation: one registry behind one interface."""
from .base import Differentiator, available_methods, get_differentiation_method
from .dequantise import Dequantised
from .methods import FiniteDifference, Kalman, SavitzkyGolay, Spline, TrendFiltered

__all__ = ["Dequantised", "Differentiator", "FiniteDifference", "Kalman", "SavitzkyGolay", "Spline",
           "TrendFiltered", "available_methods", "get_differentiation_method"]
