"""Discrepancy and hybrid models, their export and their files."""
from .discrepancy_model import DiscrepancyModel
from .model_file import load_model

__all__ = ["DiscrepancyModel", "load_model"]
