"""Sparse regression on Gram statistics."""
from .base import OPTIMIZERS, Optimizer, get_optimizer, solve_normal
from .gram import GramStatistics
from .lasso import Lasso
from .prior_only import PriorOnly
from .sr3 import SR3
from .stlsq import STLSQ

__all__ = ["OPTIMIZERS", "GramStatistics", "Lasso", "Optimizer", "SR3", "STLSQ", "get_optimizer",
           "solve_normal"]
__all__ += ["PriorOnly"]
