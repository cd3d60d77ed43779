"""PDELibrary: PySINDy's columns in PySINDy's order, composable, with exact expressions."""
import numpy as np
import pysindy as ps
import pytest
import sympy as sp

import discrepancy as dc
from discrepancy.errors import ParameterError, UnknownNameError
from discrepancy.libraries.pde import (
    derivative_name,
    library_derivative_order,
    multiindices,
    parse_derivative,
)
from discrepancy.pde.variables import FieldVariables
from discrepancy.symbolic import symbol

X = np.linspace(0, 2 * np.pi, 32, endpoint=False)


def pysindy_name(name: str) -> str:
    """PySINDy's spelling of one of our column names (u_x -> u_1, u v_xx -> u vv_11)."""
    *factors, last = name.split(" ")
    if "_" in last:
        field, axes = last.split("_")
        last = f"{field}_" + axes.replace("x", "1").replace("y", "2")
        return " ".join(factors) + last if factors else last
    return name


@pytest.mark.parametrize("ndim, n_fields, degree, order", [(1, 2, 2, 2), (1, 1, 3, 4),
                                                           (2, 1, 1, 2), (2, 2, 2, 1)])
def test_columns_and_values_equal_pysindy(ndim, n_fields, degree, order):
    rng = np.random.default_rng(ndim * 100 + order)
    x = X if ndim == 1 else np.linspace(0, 1, 8, endpoint=False)
    grid = dc.Grid(*[x] * ndim, periodic=True)
    u = rng.standard_normal((3, *grid.shape, n_fields))
    fields = ("u", "v")[:n_fields]
    variables = FieldVariables(fields, grid.names, (), order)
    lib = dc.PDELibrary(dc.PolynomialLibrary(degree, include_bias=False), order)
    lib.fit(variables.names)
    jet = variables.jet(u, None, grid, (dc.SpatialSpectral(),) * ndim)
    ours = lib.transform(jet.reshape(-1, jet.shape[-1]))

    spatial = x if ndim == 1 else np.stack(np.meshgrid(x, x, indexing="ij"), axis=-1)
    theirs_lib = ps.PDELibrary(function_library=ps.PolynomialLibrary(degree, include_bias=False),
                               derivative_order=order, spatial_grid=spatial,
                               differentiation_method=ps.SpectralDerivative)
    data = np.ascontiguousarray(np.moveaxis(u, 0, ndim))  # PySINDy: (space..., time, fields)
    theirs_lib.fit([data])
    theirs = np.moveaxis(np.asarray(theirs_lib.transform([data])[0]), ndim, 0).reshape(
        -1, ours.shape[1])
    assert [pysindy_name(n) for n in lib.get_feature_names()] == \
        theirs_lib.get_feature_names(list(fields))
    assert np.max(np.abs(ours - theirs)) < 1e-9 * np.max(np.abs(theirs))


def test_derivative_names_round_trip_and_orders():
    assert multiindices(2, 2) == [(0, 1), (0, 2), (1, 0), (1, 1), (2, 0)]
    assert derivative_name("u", (2, 1), "xy") == "u_xxy"
    assert parse_derivative("u_xxy", ["u"], "xy") == ("u", (2, 1))
    assert parse_derivative("u_yx", ["u"], "xy") is None      # x always comes first
    assert parse_derivative("w_x", ["u"], "xy") is None
    lib = dc.PDELibrary(derivative_order=3) + dc.CustomLibrary([symbol("u") * symbol("u_xxxx")])
    assert library_derivative_order(lib, ["u"], "x") == 4


def test_bias_and_interaction_options_and_no_duplicates():
    names = FieldVariables(("u",), ("x",), (), 2).names
    lib = dc.PDELibrary(dc.PolynomialLibrary(2), 2, include_bias=True).fit(names)
    exprs = lib.feature_expressions_
    assert len(exprs) == len(set(exprs))            # 1 * u_x == u_x kept once
    assert exprs[0] == 1 and symbol("u") * symbol("u_xx") in exprs
    plain = dc.PDELibrary(derivative_order=2, include_interaction=False).fit(names)
    assert plain.get_feature_names() == ["u", "u^2", "u_x", "u_xx"]


def test_composes_with_other_libraries_over_jet_variables():
    names = FieldVariables(("u", "v"), ("x",), ("f",), 2).names
    u, v, f = symbol("u"), symbol("v"), symbol("f")
    lib = (dc.PDELibrary(derivative_order=1, fields=["u"])
           + dc.PolynomialLibrary(1, include_bias=False, variables=["f"])
           * dc.CustomLibrary([u * v]))
    lib.fit(names)
    assert lib.get_feature_names()[-1] == "u v f"
    assert f * u * v in lib.feature_expressions_
    assert "v_x" not in lib.get_feature_names()


def test_bad_library_settings_are_named():
    with pytest.raises(UnknownNameError, match="derivative variables"):
        dc.PDELibrary(derivative_order=3).fit(FieldVariables(("u",), "x", (), 2).names)
    with pytest.raises(UnknownNameError, match="no derivative variables"):
        dc.PDELibrary().fit(["u", "v"])
    with pytest.raises(UnknownNameError, match=r"\['w'\]"):
        dc.PDELibrary(fields=["w"]).fit(FieldVariables(("u",), "x", (), 2).names)
    with pytest.raises(ParameterError, match="derivative_order"):
        dc.PDELibrary(derivative_order=0).fit(FieldVariables(("u",), "x", (), 2).names)
    assert sp.Symbol("u_xx", real=True) in dc.PDELibrary().fit(
        FieldVariables(("u",), "x", (), 2).names).feature_expressions_
