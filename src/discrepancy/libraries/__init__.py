"""Candidate-function libraries Θ(x, u)."""
from .base import BaseLibrary, ConcatLibrary, FeatureLibrary, TensorLibrary
from .custom import CustomLibrary
from .fourier import FourierLibrary
from .pde import PDELibrary
from .polynomial import PolynomialLibrary

__all__ = ["BaseLibrary", "ConcatLibrary", "CustomLibrary", "FeatureLibrary", "FourierLibrary",
           "PDELibrary", "PolynomialLibrary", "TensorLibrary"]
