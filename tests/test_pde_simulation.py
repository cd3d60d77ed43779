"""Method-of-lines simulation against exact solutions and an independent integrator."""
import numpy as np
import pytest

import discrepancy as dc
from discrepancy.errors import ParameterError, ShapeError
from discrepancy.symbolic import symbol

u, ux, uxx, uyy, f = (symbol(n) for n in ("u", "u_x", "u_xx", "u_yy", "f"))
X = np.linspace(0, 2 * np.pi, 64, endpoint=False)
T = np.linspace(0, 2, 21)


def test_heat_equation_decays_each_mode_exactly():
    model = dc.PDEDiscrepancyModel.prior_only([0.1 * uxx], dc.Grid(X, periodic=True))
    got = model.simulate(np.sin(2 * X) + 0.5 * np.cos(3 * X), T)[..., 0]
    exact = np.exp(-0.4 * T)[:, None] * np.sin(2 * X) + 0.5 * np.exp(-0.9 * T)[:, None] * np.cos(
        3 * X)
    assert np.max(np.abs(got - exact)) < 1e-10


def test_advection_shifts_the_profile():
    model = dc.PDEDiscrepancyModel.prior_only([-0.7 * ux], dc.Grid(X, periodic=True))
    got = model.simulate(np.exp(np.sin(X)), T)[..., 0]
    exact = np.exp(np.sin(X[None, :] - 0.7 * T[:, None]))
    assert np.max(np.abs(got - exact)) < 1e-9


def test_heat_in_two_dimensions():
    grid = dc.Grid(X, X[::2], periodic=True)
    a, b = grid.mesh()
    model = dc.PDEDiscrepancyModel.prior_only([0.05 * (uxx + symbol("u_yy"))], grid)
    got = model.simulate(np.sin(a) * np.cos(2 * b), T)[..., 0]
    assert np.max(np.abs(got[-1] - np.exp(-0.25 * 2) * np.sin(a) * np.cos(2 * b))) < 1e-10


def test_etdrk4_agrees_with_scipy_bdf_on_burgers():
    x = np.linspace(-8, 8, 64, endpoint=False)
    grid = dc.Grid(x, periodic=True)
    model = dc.PDEDiscrepancyModel.prior_only([-u * ux + 0.3 * uxx], grid)
    u0 = np.exp(-(x + 2) ** 2)
    t = np.linspace(0, 3, 16)
    fast = model.simulate(u0, t, rtol=1e-9)
    stiff = model.simulate(u0, t, method="BDF", rtol=1e-10, atol=1e-12)
    assert np.max(np.abs(fast - stiff)) < 1e-6


def test_spectral_jet_skips_only_the_derivatives_nobody_reads():
    """ETDRK4's jet transforms only the derivative orders the expressions use; those
    columns are bit for bit the full jet's, the others zero; the derivatives themselves
    are exact on a band-limited field."""
    from discrepancy.pde.simulation import SpectralJet
    from discrepancy.pde.variables import FieldVariables

    grid = dc.Grid(X, X[::2], periodic=True)
    a, b = grid.mesh()
    fields = np.stack([np.sin(a) * np.cos(2 * b), np.cos(3 * a)], axis=-1)
    variables = FieldVariables(("u", "v"), ("x", "y"), order=2)
    modes = np.fft.rfftn(fields, axes=(0, 1))
    full = SpectralJet(grid, variables)(modes)
    read = {"u", "u_xx", "v_yy"}
    part = SpectralJet(grid, variables, read)(modes)
    names = variables.names
    for i, name in enumerate(names):
        used = name in read or name in ("v", "v_xx", "u_yy")    # the same orders
        np.testing.assert_array_equal(part[..., i], full[..., i] if used else 0.0)
    np.testing.assert_allclose(full[..., names.index("u_xx")], -fields[..., 0], atol=1e-12)
    np.testing.assert_allclose(full[..., names.index("v_xx")], -9 * fields[..., 1], atol=1e-11)
    np.testing.assert_allclose(full[..., names.index("u_xy")],
                               -2 * np.cos(a) * np.sin(2 * b), atol=1e-12)


def test_callable_prior_is_integrated_by_solve_ivp_like_its_expression():
    grid = dc.Grid(X, periodic=True)

    def solver_rhs(snapshots):                  # the user's own spectral heat equation
        k = np.fft.rfftfreq(64, X[1] - X[0]) * 2 * np.pi
        return np.fft.irfft(-0.1 * k[:, None] ** 2 * np.fft.rfft(snapshots, axis=1),
                            n=64, axis=1)

    model = dc.PDEDiscrepancyModel.prior_only(solver_rhs, grid)
    got = model.simulate(np.sin(2 * X), T, rtol=1e-9, atol=1e-12)[..., 0]
    assert np.max(np.abs(got - np.exp(-0.4 * T)[:, None] * np.sin(2 * X))) < 1e-7


def test_dirichlet_ends_on_a_non_periodic_grid():
    x = np.linspace(0, np.pi, 81)
    model = dc.PDEDiscrepancyModel.prior_only([uxx], dc.Grid(x))
    got = model.simulate(np.sin(x), T, rtol=1e-9, atol=1e-12)[..., 0]
    assert np.max(np.abs(got - np.exp(-T)[:, None] * np.sin(x))) < 1e-6
    free = model.simulate(np.sin(x), T[:3], boundary="free", rtol=1e-9, atol=1e-12)
    assert free.shape == (3, 81, 1)


def test_inputs_drive_the_simulation():
    grid = dc.Grid(X, periodic=True)
    model = dc.PDEDiscrepancyModel.prior_only([0.1 * uxx + f], grid, input_names=["f"],
                                              n_inputs=1)
    got = model.simulate(np.zeros(64), T, inputs=lambda time: np.array([np.cos(time)]))
    assert np.max(np.abs(got[..., 0] - np.sin(T)[:, None])) < 1e-8
    with pytest.raises(ParameterError, match="callable f"):
        model.simulate(np.zeros(64), T)


@pytest.mark.parametrize("kwargs, error, words", [
    ({"method": "euler"}, ParameterError, "method must be one of"),
    ({"rtol": 0}, ParameterError, "rtol"),
    ({"boundary": "open"}, ParameterError, "boundary"),
])
def test_bad_simulation_options_are_named(kwargs, error, words):
    model = dc.PDEDiscrepancyModel.prior_only([uxx], dc.Grid(X, periodic=True))
    with pytest.raises(error, match=words):
        model.simulate(np.sin(X), T, **kwargs)


def test_bad_initial_fields_and_times_are_named():
    model = dc.PDEDiscrepancyModel.prior_only([uxx], dc.Grid(X[:40]))
    with pytest.raises(ShapeError, match="u0 must be"):
        model.simulate(np.zeros(39), T)
    with pytest.raises(ShapeError, match="1-D array of at least 2"):
        model.simulate(np.zeros(40), 1.0)
    with pytest.raises(ParameterError, match="periodic grid"):
        model.simulate(np.zeros(40), T, method="etdrk4")
