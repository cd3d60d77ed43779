"""PDEDiscrepancyModel: the right correction from the defaults on simulated PDEs (true
coefficients known), its API, export and errors."""
import numpy as np
import pytest
import sympy as sp

import discrepancy as dc
from discrepancy.errors import DataError, NotFittedError, ParameterError, PriorError, ShapeError
from discrepancy.symbolic import symbol

u, ux, uxx, uxxxx, v, vxx = (symbol(n) for n in ("u", "u_x", "u_xx", "u_xxxx", "v", "v_xx"))


@pytest.fixture(scope="module")
def burgers():
    """Viscous Burgers, nu = 0.1, 128 points, 81 samples."""
    x = np.linspace(-8, 8, 128, endpoint=False)
    grid = dc.Grid(x, periodic=True)
    t = np.arange(0, 8.0001, 0.1)
    truth = dc.PDEDiscrepancyModel.prior_only([-u * ux + 0.1 * uxx], grid)
    return truth.simulate(np.exp(-(x + 2) ** 2), t, rtol=1e-9)[..., 0], t, grid


def terms(model, field=0):
    names = model.get_feature_names()
    return {names[j]: model.coef_[field, j] for j in np.flatnonzero(model.coef_[field])}


@pytest.mark.parametrize("noise, form, tolerance", [(0.0, "pointwise", 1e-4),
                                                    (0.02, "weak", 1e-2)])
def test_burgers_with_a_wrong_viscosity_defaults_only(burgers, noise, form, tolerance):
    U, t, grid = burgers
    noisy = U + noise * U.std() * np.random.default_rng(3).standard_normal(U.shape)
    model = dc.PDEDiscrepancyModel(prior=[-u * ux + 0.05 * uxx]).fit(noisy, t=0.1, grid=grid)
    found = terms(model)
    assert set(found) == {"u_xx"}
    assert found["u_xx"] == pytest.approx(0.05, rel=tolerance)
    assert model.differentiation_choice_["form"] == form


def test_a_missing_reaction_in_two_fields(burgers):
    """Two coupled fields on a non-periodic grid: the prior has the diffusion only. Simulated
    on a four times finer grid (its 4th-order differences then agree with the PDE to ~1e-6)."""
    fine = np.linspace(0, 10, 321)
    true = [0.2 * uxx + u - u * v, 0.1 * vxx + u * v - 0.5 * v]
    bump = np.exp(-(fine - 5) ** 2)  # the ends rest at the steady state (0.5, 1) they are held at
    u0 = np.stack([0.5 + 0.4 * bump, 1 - 0.3 * bump], -1)
    t = np.arange(0, 4.0001, 0.02)
    U = dc.PDEDiscrepancyModel.prior_only(true, dc.Grid(fine), field_names=["u", "v"]).simulate(
        u0, t, rtol=1e-10, atol=1e-12)[:, ::4]
    model = dc.PDEDiscrepancyModel(prior=[0.2 * uxx, 0.1 * vxx], field_names=["u", "v"])
    model.fit(U, t=0.02, grid=dc.Grid(fine[::4]))
    assert terms(model, 0) == pytest.approx({"u": 1.0, "u v": -1.0}, rel=1e-3)
    assert terms(model, 1) == pytest.approx({"u v": 1.0, "v": -0.5}, rel=1e-3)


def test_several_runs_and_a_callable_prior(burgers):
    U, t, grid = burgers
    k = 2 * np.pi * np.fft.rfftfreq(128, grid.spacing[0])

    def solver(snapshots):                      # the user's spectral Burgers at nu = 0.05
        hat = np.fft.rfft(snapshots, axis=1)
        d1 = np.fft.irfft(1j * k[:, None] * hat, n=128, axis=1)
        d2 = np.fft.irfft(-(k[:, None] ** 2) * hat, n=128, axis=1)
        return -snapshots * d1 + 0.05 * d2

    model = dc.PDEDiscrepancyModel(prior=solver).fit([U[:40], U[40:]], t=0.1, grid=grid)
    assert terms(model) == pytest.approx({"u_xx": 0.05}, rel=1e-4)
    assert model.prior_.is_symbolic is False


def test_the_hybrid_simulates_the_truth_and_the_prior_does_not(burgers):
    U, t, grid = burgers
    model = dc.PDEDiscrepancyModel(prior=[-u * ux + 0.05 * uxx]).fit(U, t=0.1, grid=grid)
    hybrid = model.simulate(U[0], t)[..., 0]
    prior = dc.PDEDiscrepancyModel.prior_only([-u * ux + 0.05 * uxx], grid).simulate(U[0], t)
    assert np.max(np.abs(hybrid - U)) < 1e-4
    assert np.max(np.abs(prior[..., 0] - U)) > 0.05
    assert np.max(np.abs(model.predict(U[5:6]) - model.discrepancy(U[5:6]) - prior_rate(
        U[5:6], grid))) < 1e-10


def prior_rate(snapshots, grid):
    d = dc.SpatialSpectral()
    h = grid.spacing[0]
    s = snapshots[..., None]
    return -s * d.derivative(s, 1, 1, h, True) + 0.05 * d.derivative(s, 1, 2, h, True)


def test_print_equations_and_exact_export(burgers, capsys):
    U, t, grid = burgers
    model = dc.PDEDiscrepancyModel(prior=[-u * ux + 0.05 * uxx]).fit(U, t=0.1, grid=grid)
    model.print(3)
    out = capsys.readouterr().out
    assert out.startswith("(u)_t = prior + 0.050 u_xx") and "# pointwise form" in out
    hybrid = sp.expand(model.to_sympy()[0])
    assert hybrid.coeff(u * ux) == -1 and float(hybrid.coeff(uxx)) == pytest.approx(0.1, 1e-6)
    assert len(hybrid.args) == 2
    d = model.to_sympy(derivatives=True)[0]
    function = sp.Function("u")(symbol("t"), symbol("x"))
    assert d.has(sp.Derivative(function, (symbol("x"), 2)))
    latex = model.to_latex(3)
    assert "u_{t} &=" in latex and "u_{xx}" in latex
    assert model.complexity == 1 and model.coefficients().shape == (1, model.setup_.n_features)


def test_streamed_and_in_memory_fits_agree_and_inputs_are_used():
    x = np.linspace(0, 2 * np.pi, 48, endpoint=False)
    grid = dc.Grid(x, periodic=True)
    t = np.arange(0, 3.0001, 0.02)
    forcing = 0.5 * np.sin(t)
    truth = dc.PDEDiscrepancyModel.prior_only([0.1 * uxx + symbol("f") * u], grid,
                                              input_names=["f"], n_inputs=1)
    U = truth.simulate(1 + 0.3 * np.cos(x), t, inputs=lambda s: np.array([0.5 * np.sin(s)]),
                       rtol=1e-10)
    lib = dc.PDELibrary(derivative_order=2) + dc.PolynomialLibrary(
        1, include_bias=False, variables=["f"]) * dc.CustomLibrary([u])
    model = dc.PDEDiscrepancyModel(prior=[0.1 * uxx], feature_library=lib, input_names=["f"])
    model.fit(U, t=0.02, grid=grid, inputs=forcing)
    assert terms(model) == pytest.approx({"u f": 1.0}, rel=1e-4)


def test_errors_name_what_is_wrong(burgers):
    U, t, grid = burgers
    with pytest.raises(NotFittedError, match="fit"):
        dc.PDEDiscrepancyModel().coefficients()
    with pytest.raises(ParameterError, match="one expression per field"):
        dc.PDEDiscrepancyModel(prior=[uxx, uxx]).fit(U, t=0.1, grid=grid)
    with pytest.raises(dc.errors.UnknownNameError, match="w"):
        dc.PDEDiscrepancyModel(prior=[symbol("w")]).fit(U, t=0.1, grid=grid)
    with pytest.raises(PriorError, match="shape"):
        dc.PDEDiscrepancyModel(prior=lambda s: s[:, :3]).fit(U, t=0.1, grid=grid)
    with pytest.raises(ParameterError, match="grid must be"):
        dc.PDEDiscrepancyModel().fit(U, t=0.1, grid=np.arange(128))
    with pytest.raises(ShapeError, match="u must be"):
        dc.PDEDiscrepancyModel().fit(U[:, :100], t=0.1, grid=grid)
    with pytest.raises(ParameterError, match="clash"):
        dc.PDEDiscrepancyModel(field_names=["x"]).fit(U, t=0.1, grid=grid)
    with pytest.raises(ParameterError, match="periodic axis"):
        dc.PDEDiscrepancyModel(spatial_differentiation="spectral").fit(
            U, t=0.1, grid=dc.Grid(grid.coordinates[0]))
    with pytest.raises(ParameterError, match="differentiation_method"):
        dc.PDEDiscrepancyModel(differentiation_method=3).fit(U, t=0.1, grid=grid)
    with pytest.raises(ShapeError, match="shorter than"):
        dc.PDEDiscrepancyModel(differentiation_method=dc.SavitzkyGolay(21)).fit(
            U[:10], t=0.1, grid=grid)
    with pytest.raises(DataError, match="equally spaced"):
        dc.PDEDiscrepancyModel().fit(U[:4], t=[0, 1, 3, 4.0], grid=grid)
