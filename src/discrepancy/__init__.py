"""discrepancy: learn sparse, interpretable discrepancy models g(x, u) that correct a
first-principles model f_m(x, u), so that f_m + g predicts the real system.

Quick start::

    import discrepancy as dc
    model = dc.DiscrepancyModel(prior=f_m, feature_library=dc.PolynomialLibrary(degree=3),
                                optimizer=dc.STLSQ(threshold=0.05),
                                differentiation_method=dc.SavitzkyGolay(window_length=21))
    model.fit(x, t=0.01).print()
"""
from . import errors, io, metrics, systems
from ._version import __version__  # noqa: F401
from .data.chunks import Chunk
from .data.fields import Grid
from .data.sources import CSVFiles, HDF5Source, NPZFiles, ZarrSource
from .differentiation import (
    AutoSmoothing,
    Dequantised,
    FiniteDifference,
    Kalman,
    SavitzkyGolay,
    SmoothingSpline,
    Spectral,
    Spline,
    TrendFiltered,
    WeakForm,
)
from .differentiation.spatial import SpatialFiniteDifference, SpatialSavitzkyGolay, SpatialSpectral
from .energy import DissipationDiscrepancy, EnergyDiscrepancy
from .libraries import CustomLibrary, FourierLibrary, PDELibrary, PolynomialLibrary
from .models import Constraints, DiscrepancyModel, load_model
from .optimizers import SR3, STLSQ, GramStatistics, Lasso
from .pde import FieldSource, FieldWeakForm, PDEDiscrepancyModel

__all__ = [
    "AutoSmoothing", "CSVFiles", "Chunk", "Constraints", "CustomLibrary", "Dequantised",
    "DiscrepancyModel", "DissipationDiscrepancy", "EnergyDiscrepancy", "FiniteDifference",
    "FourierLibrary", "GramStatistics", "HDF5Source", "Kalman", "Lasso", "NPZFiles",
    "PolynomialLibrary", "SR3", "STLSQ", "SavitzkyGolay", "SmoothingSpline", "Spectral", "Spline",
    "TrendFiltered",
    "WeakForm", "ZarrSource", "errors", "io", "load_model", "metrics", "systems",
    "FieldSource", "FieldWeakForm", "Grid", "PDEDiscrepancyModel", "PDELibrary",
    "SpatialFiniteDifference", "SpatialSavitzkyGolay", "SpatialSpectral",
]
