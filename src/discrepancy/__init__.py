"""discrepancy: learn sparse, interpretable discrepancy models g(x, u) that correct a
first-principles model f_m(x, u), so that f_m + g predicts the real system.

Quick start::

    import discrepancy as dc
    model = dc.DiscrepancyModel(prior=f_m, feature_library=dc.PolynomialLibrary(degree=3),
                                optimizer=dc.STLSQ(threshold=0.05),
                                differentiation_method=dc.SavitzkyGolay(window_length=21))
    model.fit(x, t=0.01).print()
"""
from . import errors, estimation, io, metrics, selection, systems
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
from .optimizers import (
    SR3,
    STLSQ,
    ConstrainedSR3,
    EnsembleOptimizer,
    GramStatistics,
    Lasso,
    LinearConstraints,
    PriorOnly,
)
from .pde import FieldSource, FieldWeakForm, PDEDiscrepancyModel
from .procedures import choose_procedure

__all__ = [
    "AutoSmoothing", "CSVFiles", "Chunk", "ConstrainedSR3", "Constraints", "CustomLibrary",
    "Dequantised", "DiscrepancyModel", "DissipationDiscrepancy", "EnergyDiscrepancy",
    "EnsembleOptimizer", "FieldSource", "FieldWeakForm", "FiniteDifference", "FourierLibrary",
    "GramStatistics", "Grid", "HDF5Source", "Kalman", "Lasso", "LinearConstraints", "NPZFiles",
    "PDEDiscrepancyModel", "PDELibrary", "PolynomialLibrary", "PriorOnly", "SR3", "STLSQ",
    "SavitzkyGolay", "SmoothingSpline", "SpatialFiniteDifference", "SpatialSavitzkyGolay",
    "SpatialSpectral", "Spectral", "Spline", "TrendFiltered", "WeakForm", "ZarrSource",
    "choose_procedure", "errors", "estimation", "io", "load_model", "metrics", "selection",
    "systems"
]
