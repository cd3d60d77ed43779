"""Discrepancy and hybrid models, their set-up, export and files."""
from .discrepancy_model import DiscrepancyModel, load_model
from .setup import FitSetup

__all__ = ["DiscrepancyModel", "FitSetup", "load_model"]
