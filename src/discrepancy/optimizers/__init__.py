"""Sparse regression on Gram statistics."""
from .base import OPTIMIZERS, Optimizer, get_optimizer, solve_normal
from .constrained_sr3 import ConstrainedSR3
from .ensemble import EnsembleOptimizer
from .gram import GramStatistics
from .lasso import Lasso
from .linear_constraints import LinearConstraints
from .prior_only import PriorOnly
from .sr3 import SR3
from .stlsq import STLSQ
from .wrapped import WrappedOptimizer

__all__ = ["OPTIMIZERS", "ConstrainedSR3", "EnsembleOptimizer", "GramStatistics", "Lasso",
           "LinearConstraints", "Optimizer", "SR3", "STLSQ", "WrappedOptimizer", "get_optimizer",
           "solve_normal"]
__all__ += ["PriorOnly"]
