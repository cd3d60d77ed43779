"""Discrepancy and hybrid models, their set-up, export and files."""
from ..fitting.setup import FitSetup
from .core.term_constraints import Constraints
from .discrepancy_model import DiscrepancyModel, load_model

__all__ = ["Constraints", "DiscrepancyModel", "FitSetup", "load_model"]
