"""Sparse regression on Gram statistics."""
from .base import Optimizer, solve_normal
from .gram import GramStatistics
from .lasso import Lasso
from .stlsq import STLSQ

__all__ = ["GramStatistics", "Lasso", "Optimizer", "STLSQ", "solve_normal"]
