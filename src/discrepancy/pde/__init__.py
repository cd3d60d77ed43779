"""Discrepancy models for PDEs: fields on grids, spatial-derivative libraries, the weak form,
streamed and Dask fits, method-of-lines simulation."""
from .model import PDEDiscrepancyModel
from .streaming import FieldSource
from .weak import FieldWeakForm

__all__ = ["FieldSource", "FieldWeakForm", "PDEDiscrepancyModel"]
