"""File loading (CSV, NPZ, MAT, HDF5): ``discrepancy.io.load(path, ...)``."""
from .data.io import SUFFIXES, LoadedData, load

__all__ = ["SUFFIXES", "LoadedData", "load"]
