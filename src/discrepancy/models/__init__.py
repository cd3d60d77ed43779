"""Discrepancy and hybrid models, their set-up, export and files."""
from ..fitting.setup import FitSetup
from .discrepancy_model import DiscrepancyModel, load_model
from .term_constraints import Constraints

__all__ = ["Constraints", "DiscrepancyModel", "FitSetup", "load_model"]
