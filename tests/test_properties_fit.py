"""Property tests (hypothesis, the derandomised profile of conftest.py): random data, random
libraries and randomly damaged model files give the right answer, checked against numpy
least squares or a dense re-computation, or a DiscrepancyError, and nothing else."""
from __future__ import annotations

import copy
import itertools
import json
import warnings

import numpy as np
import pytest
import sympy as sp
from hypothesis import example, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

import discrepancy as dc
from discrepancy.data.trajectory import TINY_WEIGHT
from discrepancy.errors import DiscrepancyError, IllConditionedWarning
from discrepancy.symbolic import symbol

FAST = settings(max_examples=60)
numbers = st.floats(-1e3, 1e3, allow_nan=False, allow_infinity=False, width=64)
anything = st.floats(allow_nan=True, allow_infinity=True, width=64)


@st.composite
def data(draw):
    """``(x, x_dot, weights)``: a few states and targets, mostly finite (some rows may hold
    NaN or inf), optional non-negative weights."""
    m, n = draw(st.integers(2, 60)), draw(st.integers(1, 3))
    values = anything if draw(st.booleans()) and draw(st.booleans()) else numbers
    x = draw(arrays(np.float64, (m, n), elements=values))
    x_dot = draw(arrays(np.float64, (m, n), elements=numbers))
    weights = draw(st.none() | arrays(np.float64, (m,), elements=st.floats(0, 10)))
    return x, x_dot, weights


def dense_polynomial(x: np.ndarray, degree: int, bias: bool) -> np.ndarray:
    """Monomials of ``x``'s columns up to ``degree`` in PySINDy's order, by plain products."""
    columns = [np.prod(x[:, list(c)], axis=1) for d in range(0 if bias else 1, degree + 1)
               for c in itertools.combinations_with_replacement(range(x.shape[1]), d)]
    return np.column_stack(columns)


def refusal(x, x_dot, weights, degree, bias) -> bool:
    """Whether a fit must be refused: non-finite data, no columns, all weights 0, all
    columns 0, or sums of squares beyond float range, all underflowing to 0 or one of them
    subnormal (the last three over the rows of positive weight: a row of weight 0 adds
    nothing to the fit)."""
    if not np.all(np.isfinite(x)) or (degree == 0 and not bias):
        return True
    if weights is not None and not np.any(weights > 0):
        return True
    w = np.ones(len(x)) if weights is None else weights
    if w.max() < TINY_WEIGHT:          # the fit divides such weights by their largest
        w = w / w.max()
    kept = w > 0
    with np.errstate(over="ignore", invalid="ignore"):
        theta = dense_polynomial(x[kept], degree, bias)
        sums = [np.einsum("i,ij,ij->j", w[kept], theta, theta),
                np.einsum("i,ij,ij->j", w[kept], x_dot[kept], x_dot[kept])]
    tiny = np.finfo(float).tiny       # below it the sums of squares have lost precision
    return not all(np.all(np.isfinite(v)) for v in sums) or not np.any(theta) \
        or not np.any(sums[0]) or bool(np.any((sums[0] > 0) & (sums[0] < tiny)))


SUBNORMAL = np.array([5e-324, 5e-324])     # the smallest weights, relative to each other 1


@FAST
@given(sample=data(), degree=st.integers(0, 3), bias=st.booleans())
@example(sample=(np.array([[0.0], [1.0]]), np.array([[1.0], [1.0]]), SUBNORMAL), degree=1,
         bias=True)
@example(sample=(np.array([[0.0], [0.0]]), np.array([[1.5], [0.0]]), SUBNORMAL), degree=0,
         bias=True)
@example(sample=(np.array([[0.5], [0.5]]), np.array([[0.0], [0.0]]), SUBNORMAL), degree=1,
         bias=False)
@example(sample=(np.array([[1.0], [0.0]]), np.array([[1.5], [0.0]]), np.array([5e-324, 1.0])),
         degree=1, bias=False)
@example(sample=(np.array([[1.1402583e-232], [1.1402583e-232]]), np.zeros((2, 1)), None),
         degree=1, bias=False)
def test_fit_equals_numpy_least_squares_or_refuses(sample, degree, bias):
    x, x_dot, weights = sample
    model = dc.DiscrepancyModel(feature_library=dc.PolynomialLibrary(degree, include_bias=bias),
                                optimizer=dc.STLSQ(threshold=0.0, alpha=0.0))
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", IllConditionedWarning)
            model.fit(x, x_dot=x_dot, sample_weight=weights)
    except DiscrepancyError:
        assert refusal(x, x_dot, weights, degree, bias)
        return
    assert not refusal(x, x_dot, weights, degree, bias)
    theta = dense_polynomial(x, degree, bias)
    root = np.ones(len(x)) if weights is None else np.sqrt(weights)
    a, b = theta * root[:, None], x_dot * root[:, None]
    reference = np.linalg.lstsq(a, b, rcond=None)[0]
    if any(issubclass(w.category, IllConditionedWarning) for w in caught):
        # the licensed deviation: the warning must be true of the terms the fit kept
        support = np.any(model.coef_ != 0, axis=0)
        kept = a[:, support]
        norms = np.linalg.norm(kept, axis=0)
        # (more kept terms than independent rows: collinear, the condition number infinite)
        assert np.all(norms == 0) or np.linalg.matrix_rank(kept) < kept.shape[1] \
            or np.linalg.cond(kept / np.where(norms > 0, norms, 1)) ** 2 \
            > dc.models.core.conditioning.LIMIT / 10
        return
    residual, best = np.linalg.norm(a @ model.coef_.T - b), np.linalg.norm(a @ reference - b)
    scale = np.linalg.norm(b) + 1e-300
    assert residual <= best + 1e-6 * scale  # the least-squares residual, to rounding
    # unique solution (full column rank, well conditioned): the same coefficients
    if np.linalg.matrix_rank(a) == a.shape[1] and np.linalg.cond(a) < 1e6:
        np.testing.assert_allclose(model.coef_.T, reference, rtol=1e-6,
                                   atol=1e-6 * np.abs(reference).max())


@st.composite
def libraries(draw, depth=2):
    """A random library of polynomials, Fourier terms, custom expressions, sums, products."""
    leaf = st.one_of(
        st.builds(dc.PolynomialLibrary, st.integers(0, 3), include_bias=st.booleans()),
        st.builds(dc.FourierLibrary, st.integers(1, 3)),
        st.builds(lambda e: dc.CustomLibrary([e]), st.sampled_from(
            [sp.exp(symbol("a")), sp.Abs(symbol("b")) * symbol("a"), sp.tanh(symbol("a"))])))
    if depth == 0:
        return draw(leaf)
    left, right = draw(libraries(depth=depth - 1)), draw(libraries(depth=depth - 1))
    return draw(st.sampled_from([left, left + right, left * right]))


@FAST
@given(library=libraries(), z=arrays(np.float64, (5, 2), elements=st.floats(-2, 2)))
def test_library_columns_equal_their_expressions_evaluated_by_sympy(library, z):
    try:
        theta = library.fit(["a", "b"]).transform(z)
    except DiscrepancyError:  # a library with no columns
        return
    a, b = symbol("a"), symbol("b")
    for j, expr in enumerate(library.feature_expressions_):
        for i, (va, vb) in enumerate(z):
            exact = float(expr.subs({a: sp.Float(va, 30), b: sp.Float(vb, 30)}).evalf(30))
            assert np.isclose(theta[i, j], exact, rtol=1e-9, atol=1e-12), (expr, va, vb)
    assert len(set(library.feature_expressions_)) == theta.shape[1]  # no duplicate columns


T = np.arange(200) * 0.01
X = np.c_[np.sin(T), np.cos(T)]
FILE = dc.DiscrepancyModel(prior=[symbol("x2"), sp.Integer(0)],
                           feature_library=dc.PolynomialLibrary(2) + dc.FourierLibrary(1),
                           differentiation_method="finite_difference").fit(X, 0.01).to_state()
json_values = st.recursive(st.none() | st.booleans() | st.integers(-10**40, 10**40) | anything
                           | st.text(max_size=5),
                           lambda inner: st.lists(inner, max_size=4) | st.dictionaries(
                               st.text(max_size=5), inner, max_size=3), max_leaves=8)


def paths(doc, prefix=()):
    """Every position inside the document (keys and list indices)."""
    items = doc.items() if isinstance(doc, dict) else enumerate(doc) if isinstance(doc, list) \
        else []
    for key, value in items:
        yield (*prefix, key)
        yield from paths(value, (*prefix, key))


PATHS = list(paths(FILE))


@FAST
@given(where=st.sampled_from(PATHS), value=json_values)
def test_damaged_model_files_load_right_or_raise_a_discrepancy_error(tmp_path_factory, where,
                                                                     value):
    doc = copy.deepcopy(FILE)
    target = doc
    for key in where[:-1]:
        target = target[key]
    target[where[-1]] = value
    path = tmp_path_factory.mktemp("files") / "m.json"
    path.write_text(json.dumps(doc))
    try:
        model = dc.load_model(path)
    except DiscrepancyError:
        return
    prediction = model.predict(X)  # whatever loaded is a working model of the same shape
    assert prediction.shape == X.shape
    if doc["coefficients"] == FILE["coefficients"] and doc["features"] == FILE["features"] \
            and doc["prior"] == FILE["prior"]:
        reference = dc.DiscrepancyModel.from_state(FILE)
        np.testing.assert_allclose(prediction, reference.predict(X), rtol=1e-12)


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_one_bad_value_is_refused_whatever_the_library(bad):
    x = X.copy()
    x[7, 1] = bad
    for library in (dc.PolynomialLibrary(3), dc.FourierLibrary(2), "poly(1)*fourier(1)"):
        with pytest.raises(DiscrepancyError, match=r"x must be finite.*row 7, column 1"):
            dc.DiscrepancyModel(feature_library=library).fit(x, 0.01)
