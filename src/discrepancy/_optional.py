"""Optional dependencies: imported only where needed, with a clear error when missing.

``pip install discrepancy`` brings numpy, scipy, sympy and ``derivative``: enough to fit,
simulate, save and export to sympy/LaTeX. The rest comes with extras: ``[control]``
(CasADi: ``to_casadi``, trajectory optimisation), ``[scale]`` (Dask, distributed, zarr,
h5py: clusters and large files), ``[plots]`` (matplotlib, pillow), ``[paper]`` (all).
"""
from __future__ import annotations

import importlib
import importlib.util

from .errors import MissingDependencyError

#: module -> the extra that installs it
EXTRAS = {"casadi": "control", "dask": "scale", "distributed": "scale", "zarr": "scale",
          "h5py": "scale", "matplotlib": "plots", "PIL": "plots"}


def require(module: str, *, purpose: str):
    """Import and return ``module``, or raise MissingDependencyError naming the extra."""
    try:
        return importlib.import_module(module)
    except ImportError:
        extra = EXTRAS.get(module.split(".")[0], "paper")
        raise MissingDependencyError(
            f"{purpose} needs {module.split('.')[0]}, which is not installed; install it with "
            f"pip install 'discrepancy[{extra}]'") from None


def missing(module: str) -> bool:
    """Whether ``module`` cannot be imported (for optional fast paths that fall back)."""
    return importlib.util.find_spec(module) is None
