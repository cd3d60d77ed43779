"""PySINDy's PDE-FIND and weak form on the same fields, for the side-by-side tables.

PySINDy has no prior: it identifies the whole right-hand side, and the discrepancy it
implies is its coefficients minus the prior's. Settings matched to ours: the same library
(PDELibrary of the same polynomial degree and derivative order), spectral spatial
derivatives on periodic grids, second-order finite differences in time (PDE-FIND), and the
same fixed STLSQ threshold; the weak form uses PySINDy's defaults for its sub-domains
(``K`` random boxes of half-width ``L / 20``, ``p = 4``) with ``K`` raised to 500 and its
random centres seeded. A constant column is the library's own (``include_bias``), so no
column appears twice (``1 * u_x``). Fields are passed as PySINDy wants them,
``(space..., time, fields)``.
"""
from __future__ import annotations

import time
import warnings

import numpy as np


def _names(names: list[str], fields: list[str], coordinates: list[str]) -> list[str]:
    """PySINDy's column names in ours (``u_11`` -> ``u_xx``, ``u vu_1`` -> ``u v u_x``)."""
    import re

    alternatives = "|".join(sorted(map(re.escape, fields), key=len, reverse=True))
    out = []
    for name in names:
        match = re.match(rf"^(.*?)({alternatives})_(\d+)$", name)
        if match:
            prefix, field, axes = match.groups()
            letters = "".join(coordinates[int(a) - 1] for a in axes)
            name = (prefix.strip() + " " if prefix.strip() else "") + f"{field}_{letters}"
        out.append(name)
    return out


def _library(kind: str, grid, t, degree: int, order: int, include_bias: bool):
    import pysindy as ps

    functions = ps.PolynomialLibrary(degree=degree, include_bias=False)
    spatial = grid.coordinates[0] if grid.ndim == 1 else np.stack(grid.mesh(), axis=-1)
    if kind == "pde-find":
        return ps.PDELibrary(function_library=functions, derivative_order=order,
                             spatial_grid=spatial, include_bias=include_bias,
                             differentiation_method=ps.SpectralDerivative
                             if all(grid.periodic) else ps.FiniteDifference)
    mesh = np.meshgrid(*grid.coordinates, t, indexing="ij")
    np.random.seed(0)  # noqa: NPY002 (PySINDy draws its sub-domains from numpy's global one)
    return ps.WeakPDELibrary(function_library=functions, derivative_order=order,
                             spatiotemporal_grid=np.stack(mesh, axis=-1), K=500,
                             include_bias=include_bias)


def fit(kind: str, fields: np.ndarray, t: np.ndarray, grid, *, field_names, degree: int,
        order: int, threshold: float, include_bias: bool = False) -> dict:
    """PySINDy's ``kind`` (``"pde-find"`` or ``"weak"``) on fields ``(m, *shape, n)``:
    ``{"coefficients": {field: {term: value}}, "fit_seconds": CPU seconds}``."""
    import pysindy as ps

    data = np.ascontiguousarray(np.moveaxis(fields, 0, grid.ndim))
    lib = _library(kind, grid, t, degree, order, include_bias)
    model = ps.SINDy(feature_library=lib, optimizer=ps.STLSQ(threshold=threshold, alpha=1e-5))
    start = time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model.fit(data, t=float(t[1] - t[0]), feature_names=list(field_names))
    seconds = time.process_time() - start
    names = _names(model.get_feature_names(), list(field_names), list(grid.names))
    coef = model.coefficients()
    return {"coefficients": {f: {names[j]: float(coef[i, j]) for j in np.flatnonzero(coef[i])}
                             for i, f in enumerate(field_names)},
            "fit_seconds": seconds}
