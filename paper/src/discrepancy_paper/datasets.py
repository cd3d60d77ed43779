"""The measured data the examples use, shipped with this package (see each folder's
README for its source, licence and citation)."""
from __future__ import annotations

from importlib.resources import files
from pathlib import Path

from discrepancy.errors import DataError

DATASETS = {"double_pendulum", "cascaded_tanks", "silverbox"}


def data_file(dataset: str, name: str) -> Path:
    """Path of file ``name`` of ``dataset`` (a folder of ``discrepancy_paper/data``)."""
    if dataset not in DATASETS:
        raise DataError(f"unknown dataset {dataset!r}; the package holds {sorted(DATASETS)}")
    path = Path(str(files("discrepancy_paper").joinpath("data", dataset, name)))
    if not path.is_file():
        raise DataError(f"{dataset}/{name} is missing from the installed package; reinstall "
                        "it from the repository (pip install -e paper)")
    return path
