"""Feature libraries: every column against sympy, order and values against PySINDy."""
from __future__ import annotations

import warnings
from math import comb

import numpy as np
import pysindy as ps
import pytest
import sympy as sp
from hypothesis import given
from hypothesis import strategies as st

import discrepancy as dc
from discrepancy.errors import NotFittedError, ParameterError, ShapeError, UnknownNameError
from discrepancy.symbolic import symbol

NAMES = ["x1", "x2", "u"]


def sympy_columns(lib, Z, functions=None):
    """Θ evaluated column by column from the library's sympy expressions with sympy.lambdify."""
    syms = [symbol(n) for n in lib.names_]
    modules = [functions or {}, "numpy"]
    cols = []
    for e in lib.feature_expressions_:
        f = sp.lambdify(syms, e, modules=modules)
        cols.append(np.broadcast_to(np.asarray(f(*Z.T), dtype=float), (Z.shape[0],)))
    return np.column_stack(cols)


def check_against_sympy(lib, Z, functions=None):
    theta = lib.transform(Z)
    assert theta.shape == (Z.shape[0], lib.n_features_) == (Z.shape[0],
                                                           len(lib.feature_expressions_))
    assert len(lib.get_feature_names()) == lib.n_features_
    np.testing.assert_allclose(theta, sympy_columns(lib, Z, functions), rtol=1e-12, atol=1e-12)
    return theta


x1, x2, u = (symbol(n) for n in NAMES)

LIBRARIES = {
    "poly3": lambda: dc.PolynomialLibrary(degree=3),
    "poly2_nobias": lambda: dc.PolynomialLibrary(degree=2, include_bias=False),
    "poly3_interaction": lambda: dc.PolynomialLibrary(degree=3, interaction_only=True),
    "fourier2": lambda: dc.FourierLibrary(n_frequencies=2),
    "fourier_sin_only": lambda: dc.FourierLibrary(n_frequencies=3, include_cos=False),
    "fourier_given": lambda: dc.FourierLibrary(frequencies=[0.5, 2.0], variables=["x1"]),
    "custom_exprs": lambda: dc.CustomLibrary(expressions=[
        sp.sin(x1) * x2, sp.exp(-x2**2), x1 / (1 + x2**2), sp.tanh(u) - 3, sp.Abs(x1) * u]),
    "custom_functions": lambda: dc.CustomLibrary(
        functions={"sq": np.square, "cube": lambda v: v**3}, variables=["x1", "u"]),
    "concat": lambda: dc.PolynomialLibrary(degree=2) + dc.FourierLibrary(n_frequencies=1),
    "tensor": lambda: dc.FourierLibrary(variables=["x1"]) * dc.PolynomialLibrary(
        degree=1, include_bias=False, variables=["u"]),
    "nested": lambda: (dc.PolynomialLibrary(degree=1, variables=[0, 1])
                       + dc.FourierLibrary(variables=[0]) * dc.PolynomialLibrary(
                           degree=2, include_bias=False, variables=[2])),
}


@pytest.mark.parametrize("name", sorted(LIBRARIES))
def test_every_column_equals_sympy_evaluation(name, rng):
    lib = LIBRARIES[name]().fit(NAMES)
    Z = rng.uniform(-2, 2, size=(64, 3))
    check_against_sympy(lib, Z, functions={"sq": np.square, "cube": lambda v: v**3})


def _pysindy_names(names):
    return [n.replace("x", "z") for n in names]


@pytest.mark.parametrize("n_vars", [1, 2, 3, 4])
@pytest.mark.parametrize("degree", [1, 2, 3, 4])
@pytest.mark.parametrize("include_bias, interaction_only", [(True, False), (False, False),
                                                            (True, True), (False, True)])
def test_polynomial_library_equals_pysindy(n_vars, degree, include_bias, interaction_only, rng):
    Z = rng.normal(size=(40, n_vars))
    names = [f"x{i + 1}" for i in range(n_vars)]
    kw = dict(degree=degree, include_bias=include_bias, interaction_only=interaction_only)
    ours = dc.PolynomialLibrary(**kw).fit(names)
    peer = ps.PolynomialLibrary(**kw).fit(Z)
    np.testing.assert_allclose(ours.transform(Z), np.asarray(peer.transform(Z)),
                               rtol=1e-13, atol=1e-13)
    assert ours.get_feature_names() == peer.get_feature_names(names)


@pytest.mark.parametrize("n_vars", [1, 3])
@pytest.mark.parametrize("n_frequencies", [1, 2, 3])
@pytest.mark.parametrize("include_sin, include_cos", [(True, True), (True, False),
                                                      (False, True)])
def test_fourier_library_equals_pysindy(n_vars, n_frequencies, include_sin, include_cos, rng):
    Z = rng.uniform(-4, 4, size=(40, n_vars))
    kw = dict(n_frequencies=n_frequencies, include_sin=include_sin, include_cos=include_cos)
    ours = dc.FourierLibrary(**kw).fit([f"x{i + 1}" for i in range(n_vars)])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        peer = ps.FourierLibrary(**kw).fit(Z)
    # pysindy names are sin(1 x0); compare values and order, which is what the fit sees
    np.testing.assert_allclose(ours.transform(Z), np.asarray(peer.transform(Z)),
                               rtol=1e-13, atol=1e-13)


def test_feature_names_are_readable():
    lib = (dc.PolynomialLibrary(degree=3, variables=["x1", "x2"])
           + dc.FourierLibrary(variables=["x1"]) * dc.PolynomialLibrary(
               degree=1, include_bias=False, variables=["u"])).fit(NAMES)
    names = lib.get_feature_names()
    for expected in ("1", "x1", "x2", "x1^2 x2", "x1 x2^2", "x2^3", "sin(x1) u", "cos(x1) u"):
        assert expected in names


def test_concatenation_stacks_columns_in_order(rng):
    a, b = dc.PolynomialLibrary(degree=2), dc.FourierLibrary(n_frequencies=2)
    both = (a + b).fit(NAMES)
    Z = rng.normal(size=(30, 3))
    ta, tb = a.fit(NAMES).transform(Z), b.fit(NAMES).transform(Z)
    np.testing.assert_array_equal(both.transform(Z), np.hstack([ta, tb]))
    assert both.feature_expressions_ == a.feature_expressions_ + b.feature_expressions_
    # + is associative in columns: (a + b) + c == a + (b + c)
    c = dc.CustomLibrary(expressions=[sp.exp(x1)])
    left, right = ((a + b) + c).fit(NAMES), (a + (b + c)).fit(NAMES)
    assert left.feature_expressions_ == right.feature_expressions_
    np.testing.assert_array_equal(left.transform(Z), right.transform(Z))


def test_duplicates_are_dropped_keeping_the_first(rng):
    lib = (dc.PolynomialLibrary(degree=2) + dc.PolynomialLibrary(degree=1)
           + dc.CustomLibrary(expressions=[x1 * x2, sp.sin(x1)])
           + dc.FourierLibrary(variables=["x1"])).fit(NAMES)
    exprs = lib.feature_expressions_
    assert len(exprs) == len(set(exprs))
    poly = dc.PolynomialLibrary(degree=2).fit(NAMES).feature_expressions_
    assert exprs == [*poly, sp.sin(x1), sp.cos(x1)]
    check_against_sympy(lib, rng.normal(size=(20, 3)))


def test_tensor_product_forms_all_products_without_duplicates(rng):
    lin = dc.PolynomialLibrary(degree=1, include_bias=False, variables=["x1", "x2"])
    square = (lin * lin).fit(NAMES)
    # x1*x1, x1*x2, x2*x1, x2*x2 -> three distinct monomials
    assert square.feature_expressions_ == [x1**2, x1 * x2, x2**2]
    Z = rng.normal(size=(25, 3))
    np.testing.assert_allclose(square.transform(Z),
                               np.column_stack([Z[:, 0]**2, Z[:, 0] * Z[:, 1], Z[:, 1]**2]),
                               rtol=1e-14)
    control = (dc.FourierLibrary(n_frequencies=2, variables=["x1"])
               * dc.PolynomialLibrary(degree=1, include_bias=False, variables=["u"])).fit(NAMES)
    assert control.feature_expressions_ == [sp.sin(x1) * u, sp.cos(x1) * u,
                                            sp.sin(2 * x1) * u, sp.cos(2 * x1) * u]


@pytest.mark.parametrize("variables", [["x2", "u"], [1, 2], ["u", "x2"]])
def test_variables_restrict_the_library(variables, rng):
    lib = dc.PolynomialLibrary(degree=2, variables=variables).fit(NAMES)
    used = set().union(*(e.free_symbols for e in lib.feature_expressions_))
    assert used == {x2, u}
    assert lib.n_features_ == comb(2 + 2, 2)
    Z = rng.normal(size=(30, 3))
    theta = check_against_sympy(lib, Z)
    # changing the excluded variable leaves every column unchanged
    Z2 = Z.copy()
    Z2[:, 0] = rng.normal(size=30)
    np.testing.assert_array_equal(lib.transform(Z2), theta)


def test_unknown_variable_is_refused():
    with pytest.raises(UnknownNameError, match="x3"):
        dc.PolynomialLibrary(variables=["x3"]).fit(NAMES)
    with pytest.raises(UnknownNameError, match="7"):
        dc.FourierLibrary(variables=[7]).fit(NAMES)


def test_custom_expression_with_an_unknown_symbol_is_refused():
    with pytest.raises(UnknownNameError, match="y"):
        dc.CustomLibrary(expressions=[x1 * sp.Symbol("y")]).fit(NAMES)


def test_custom_expressions_accept_plain_sympy_symbols(rng):
    # symbols created without real=True must still be matched to the variables by name
    a, b = sp.symbols("x1 x2")
    lib = dc.CustomLibrary(expressions=[a * b, sp.cos(a)]).fit(NAMES)
    Z = rng.normal(size=(10, 3))
    np.testing.assert_allclose(lib.transform(Z),
                               np.column_stack([Z[:, 0] * Z[:, 1], np.cos(Z[:, 0])]), rtol=1e-14)


def test_interaction_only_and_include_bias(rng):
    lib = dc.PolynomialLibrary(degree=3, interaction_only=True, include_bias=False).fit(NAMES)
    for e in lib.feature_expressions_:
        assert all(sp.degree(e, s) <= 1 for s in (x1, x2, u))
        assert not e.is_number
    assert set(lib.feature_expressions_) == {x1, x2, u, x1 * x2, x1 * u, x2 * u, x1 * x2 * u}
    with_bias = dc.PolynomialLibrary(degree=3, interaction_only=True).fit(NAMES)
    assert with_bias.feature_expressions_[0] == 1
    np.testing.assert_array_equal(with_bias.transform(rng.normal(size=(5, 3)))[:, 0], 1.0)


def test_transform_before_fit_and_wrong_columns():
    lib = dc.PolynomialLibrary(degree=2)
    with pytest.raises(NotFittedError):
        lib.transform(np.zeros((3, 3)))
    lib.fit(NAMES)
    with pytest.raises(ShapeError, match=r"\(m, 3\)"):
        lib.transform(np.zeros((3, 2)))


@pytest.mark.parametrize("make", [lambda: dc.PolynomialLibrary(degree=0, include_bias=False),
                                  lambda: dc.CustomLibrary(expressions=[]),
                                  lambda: dc.CustomLibrary(functions={})],
                         ids=["poly_degree0_nobias", "custom_no_expressions",
                              "custom_no_functions"])
def test_empty_library_is_refused(make):
    with pytest.raises(ParameterError, match="at least one column|non-empty"):
        make().fit(NAMES)


def test_bad_library_parameters():
    for lib in (dc.PolynomialLibrary(degree=-1), dc.PolynomialLibrary(degree=1.5),
                dc.FourierLibrary(n_frequencies=0),
                dc.FourierLibrary(include_sin=False, include_cos=False),
                dc.CustomLibrary(functions={"log": np.log1p}),  # would shadow sympy's log
                dc.CustomLibrary(functions={"not a name": np.abs})):
        with pytest.raises(ParameterError):
            lib.fit(NAMES)
    with pytest.raises(ParameterError):
        dc.PolynomialLibrary() + np.ones(3)


def test_constructor_stores_arguments_only():
    lib = dc.PolynomialLibrary(degree=-5, variables=["nope"])  # validated at fit, not here
    assert lib.degree == -5 and lib.variables == ["nope"]
    assert not hasattr(lib, "feature_expressions_")


# --------------------------------------------------------------------- properties

@given(n_vars=st.integers(1, 4), degree=st.integers(0, 4), bias=st.booleans(),
       interaction=st.booleans(), seed=st.integers(0, 2**16))
def test_polynomial_library_property(n_vars, degree, bias, interaction, seed):
    names = [f"v{i}" for i in range(n_vars)]
    lib = dc.PolynomialLibrary(degree=degree, include_bias=bias, interaction_only=interaction)
    # number of monomials of total degree <= d in k variables (or of distinct-variable products)
    count = sum(comb(n_vars, d) if interaction else comb(n_vars + d - 1, d)
                for d in range(0 if bias else 1, degree + 1))
    if count == 0:
        with pytest.raises(ParameterError):
            lib.fit(names)
        return
    lib.fit(names)
    assert lib.n_features_ == count
    assert len(set(lib.feature_expressions_)) == count
    Z = np.random.default_rng(seed).uniform(-1.5, 1.5, size=(20, n_vars))
    check_against_sympy(lib, Z)


def _library(kind, variables, k):
    if kind == "poly":
        return dc.PolynomialLibrary(degree=k, variables=variables)
    if kind == "fourier":
        return dc.FourierLibrary(n_frequencies=k, variables=variables)
    return dc.CustomLibrary(expressions=[symbol(v) ** (k + 1) for v in variables])


library_spec = st.tuples(st.sampled_from(["poly", "fourier", "custom"]),
                         st.lists(st.sampled_from(NAMES), min_size=1, max_size=3, unique=True),
                         st.integers(1, 3))


@given(specs=st.lists(library_spec, min_size=2, max_size=4), seed=st.integers(0, 2**16))
def test_concatenation_preserves_every_column(specs, seed):
    parts = [_library(*s) for s in specs]
    total = parts[0]
    for p in parts[1:]:
        total = total + p
    total.fit(NAMES)
    Z = np.random.default_rng(seed).uniform(-2, 2, size=(15, 3))
    theta = total.transform(Z)
    column_of = dict(zip(total.feature_expressions_, theta.T, strict=True))
    assert len(column_of) == theta.shape[1]  # no duplicate expressions
    expected = []
    for p in parts:
        p.fit(NAMES)
        for e, col in zip(p.feature_expressions_, p.transform(Z).T, strict=True):
            # same expression from another library may be computed another way (x*x*x, x**3)
            np.testing.assert_allclose(column_of[e], col, rtol=1e-13, atol=1e-13)
            if e not in expected:
                expected.append(e)
    assert total.feature_expressions_ == expected


@given(left=library_spec, right=library_spec, seed=st.integers(0, 2**16))
def test_tensor_product_property(left, right, seed):
    a, b = _library(*left), _library(*right)
    prod = (a * b).fit(NAMES)
    Z = np.random.default_rng(seed).uniform(-2, 2, size=(15, 3))
    check_against_sympy(prod, Z)
    a.fit(NAMES)
    b.fit(NAMES)
    products = {ea * eb for ea in a.feature_expressions_ for eb in b.feature_expressions_}
    assert set(prod.feature_expressions_) == products
    assert len(prod.feature_expressions_) == len(products)


def _random_expressions():
    atoms = st.one_of(st.sampled_from([x1, x2, u]), st.integers(-4, 4).map(sp.Integer),
                      st.fractions(min_value=-2, max_value=2, max_denominator=5).map(sp.Rational))
    unary = st.sampled_from([sp.sin, sp.cos, sp.exp, sp.tanh, sp.Abs, sp.atan, sp.cosh])

    def combine(children):
        return st.one_of(
            st.lists(children, min_size=2, max_size=3).map(lambda a: sp.Add(*a)),
            st.lists(children, min_size=2, max_size=3).map(lambda a: sp.Mul(*a)),
            st.tuples(children, st.integers(-2, 3)).map(lambda a: sp.Pow(a[0], a[1])),
            st.tuples(children, st.sampled_from([sp.Rational(1, 2), sp.Rational(3, 2)])).map(
                lambda a: sp.Pow(sp.Abs(a[0]) + 1, a[1])),
            st.tuples(unary, children).map(lambda a: a[0](a[1])))

    return st.recursive(atoms, combine, max_leaves=6)


@given(exprs=st.lists(_random_expressions(), min_size=1, max_size=4), seed=st.integers(0, 2**16))
def test_custom_expressions_property(exprs, seed):
    """Every sympy expression a user can write evaluates as sympy.lambdify does."""
    exprs = [e for e in exprs if not e.has(sp.zoo, sp.nan, sp.oo, -sp.oo)
             and not e.atoms(sp.AccumBounds)]  # e.g. atan(1/0): an interval, not a value
    if not exprs:
        return
    lib = dc.CustomLibrary(expressions=exprs).fit(NAMES)
    Z = np.random.default_rng(seed).uniform(-2, 2, size=(12, 3))
    with np.errstate(all="ignore"):
        theta = lib.transform(Z)
        expected = sympy_columns(lib, Z)
    assert theta.shape == expected.shape
    np.testing.assert_allclose(theta, expected, rtol=1e-9, atol=1e-12, equal_nan=True)
