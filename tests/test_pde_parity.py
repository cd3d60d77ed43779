"""PDE-FIND with identical settings: our coefficients equal PySINDy's.

Identical settings: no prior, PySINDy's library (PDELibrary of the same polynomials and
derivative order), its time derivative (second-order finite differences), the same spatial
derivatives (spectral, or its finite differences) and a fixed STLSQ threshold. Our fit
works on Gram statistics, PySINDy's on the whole matrix; both solve the same equations.
"""
import warnings

import numpy as np
import pysindy as ps
import pytest

import discrepancy as dc
from discrepancy.symbolic import symbol


@pytest.fixture(scope="module")
def burgers():
    u, ux, uxx = symbol("u"), symbol("u_x"), symbol("u_xx")
    x = np.linspace(-8, 8, 128, endpoint=False)
    grid = dc.Grid(x, periodic=True)
    t = np.arange(0, 5.0001, 0.05)
    truth = dc.PDEDiscrepancyModel.prior_only([-u * ux + 0.1 * uxx], grid)
    return truth.simulate(np.exp(-(x + 2) ** 2), t, rtol=1e-9)[..., 0], x, t, grid


@pytest.mark.parametrize("spatial", ["spectral", "finite_difference"])
@pytest.mark.parametrize("noise", [0.0, 0.002])
def test_pde_find_equals_pysindy(burgers, spatial, noise):
    U, x, t, grid = burgers
    U = U + noise * np.random.default_rng(0).standard_normal(U.shape)
    dt = t[1] - t[0]
    ours = dc.PDEDiscrepancyModel(
        feature_library=dc.PDELibrary(dc.PolynomialLibrary(2, include_bias=False), 2),
        optimizer=dc.STLSQ(threshold=0.02, alpha=1e-5),
        differentiation_method=dc.FiniteDifference(),
        spatial_differentiation=dc.SpatialSpectral() if spatial == "spectral"
        else dc.SpatialFiniteDifference(2)).fit(U, t=dt, grid=grid)
    method = ps.SpectralDerivative if spatial == "spectral" else ps.FiniteDifference
    kwargs = {} if spatial == "spectral" else {"diff_kwargs": {"periodic": True}}
    lib = ps.PDELibrary(function_library=ps.PolynomialLibrary(2, include_bias=False),
                        derivative_order=2, spatial_grid=x, differentiation_method=method,
                        **kwargs)
    theirs = ps.SINDy(feature_library=lib, optimizer=ps.STLSQ(threshold=0.02, alpha=1e-5))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        theirs.fit(U.T[:, :, None], t=dt)
    assert ours.get_feature_names() == ["u", "u^2", "u_x", "u_xx", "u u_x", "u^2 u_x",
                                        "u u_xx", "u^2 u_xx"]
    coef = theirs.coefficients()
    assert np.count_nonzero(coef) >= 2
    assert np.array_equal(ours.coef_ != 0, coef != 0)
    assert np.max(np.abs(ours.coef_ - coef)) < 1e-8 * np.max(np.abs(coef))
    if noise == 0 and spatial == "spectral":
        c = dict(zip(ours.get_feature_names(), ours.coef_[0], strict=True))
        assert c["u u_x"] == pytest.approx(-1, rel=2e-3) and c["u_xx"] == pytest.approx(
            0.1, rel=2e-3)
