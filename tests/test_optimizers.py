"""Sparse regression: STLSQ against PySINDy, Lasso against scikit-learn, Gram statistics."""
from __future__ import annotations

import warnings

import numpy as np
import pysindy as ps
import pytest
import scipy.linalg
from hypothesis import given
from hypothesis import strategies as st
from sklearn.linear_model import Lasso as SklearnLasso

import discrepancy as dc
from discrepancy.errors import NotFittedError, ParameterError, ShapeError
from discrepancy.optimizers.base import _cholesky_solve


def problem(seed, m=300, p=10, n=3, noise=0.01, spread=True):
    """Random Θ (columns of very different scales when ``spread``) and y = Θ Ξ + noise."""
    rng = np.random.default_rng(seed)
    theta = rng.normal(size=(m, p))
    if spread:
        theta *= 10.0 ** rng.uniform(-1.5, 1.5, size=p)
    xi = rng.normal(size=(p, n)) * (rng.random((p, n)) < 0.4)
    y = theta @ xi + noise * rng.normal(size=(m, n))
    return theta, y, xi


THRESHOLDS = [0.02, 0.1, 0.3, 3.0]


def quiet(f, *args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return f(*args, **kwargs)


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("normalize_columns", [False, True])
@pytest.mark.parametrize("alpha", [0.0, 0.05, 2.0])
@pytest.mark.parametrize("threshold", THRESHOLDS)
@pytest.mark.parametrize("unbias", [True, False])
def test_stlsq_equals_pysindy(seed, normalize_columns, alpha, threshold, unbias):
    theta, y, _ = problem(seed)
    kw = dict(threshold=threshold, alpha=alpha, normalize_columns=normalize_columns,
              unbias=unbias, max_iter=20)
    peer = quiet(ps.STLSQ(**kw).fit, theta, y).coef_
    ours = quiet(dc.STLSQ(**kw).fit, theta, y).coef_
    assert ours.shape == peer.shape == (3, 10)
    np.testing.assert_allclose(ours, peer, rtol=0, atol=1e-8)
    np.testing.assert_array_equal(ours != 0, peer != 0)


def test_the_pysindy_comparison_exercises_thresholding():
    """Guard against a vacuous comparison: the grid must contain sparse and non-trivial fits."""
    for seed in range(4):
        theta, y, _ = problem(seed)
        for normalize in (False, True):
            fractions = [np.count_nonzero(quiet(dc.STLSQ(threshold=h, normalize_columns=normalize)
                                                .fit, theta, y).coef_) / 30 for h in THRESHOLDS]
            assert any(0.1 < f < 0.7 for f in fractions), (seed, normalize, fractions)


def test_stlsq_single_target_matches_pysindy():
    theta, y, _ = problem(7, n=1)
    peer = quiet(ps.STLSQ(threshold=0.1).fit, theta, y[:, 0]).coef_
    ours = dc.STLSQ(threshold=0.1).fit(theta, y[:, 0]).coef_
    assert ours.shape == (1, 10)
    np.testing.assert_allclose(ours, np.atleast_2d(peer), atol=1e-8)


@pytest.mark.parametrize("seed", range(3))
def test_stlsq_recovers_exact_sparse_coefficients(seed):
    theta, y, xi = problem(seed, noise=0.0, spread=False)
    xi[np.abs(xi) < 0.2] = 0.0  # keep every true term above the threshold
    y = theta @ xi
    coef = dc.STLSQ(threshold=0.1, alpha=0.0).fit(theta, y).coef_
    np.testing.assert_allclose(coef, xi.T, atol=1e-10)


@pytest.mark.parametrize("optimizer", [dc.STLSQ(threshold=0.1),
                                       dc.STLSQ(threshold=0.1, normalize_columns=True),
                                       dc.Lasso(alpha=0.01),
                                       dc.Lasso(alpha=0.01, normalize_columns=True, unbias=True)],
                         ids=["stlsq", "stlsq_norm", "lasso", "lasso_norm_unbias"])
def test_fit_gram_equals_fit(optimizer):
    theta, y, _ = problem(3)
    direct = quiet(optimizer.fit, theta, y).coef_.copy()
    gram, rhs = theta.T @ theta, theta.T @ y
    from_stats = quiet(optimizer.fit_gram, gram, rhs, n_samples=theta.shape[0]).coef_
    np.testing.assert_allclose(from_stats, direct, rtol=1e-10, atol=1e-12)


def test_fit_returns_self_and_sets_support():
    theta, y, _ = problem(1)
    opt = dc.STLSQ(threshold=0.1)
    assert opt.fit(theta, y) is opt
    np.testing.assert_array_equal(opt.ind_, opt.coef_ != 0)


def test_stlsq_solves_ill_conditioned_polynomial_gram():
    # monomials up to degree 5 of a variable in [0, 10]: columns span 5 orders of magnitude
    z = np.linspace(0, 10, 400)
    theta = np.column_stack([z**k for k in range(6)])
    xi = np.array([0.0, 1.5, 0.0, -0.25, 0.0, 0.001])
    coef = dc.STLSQ(threshold=1e-4, alpha=0.0).fit(theta, theta @ xi).coef_[0]
    np.testing.assert_allclose(coef, xi, rtol=1e-7, atol=1e-9)


# ------------------------------------------------------------------------ Lasso

@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("alpha", [1e-3, 1e-2, 1e-1])
def test_lasso_equals_scikit_learn(seed, alpha):
    theta, y, _ = problem(seed, spread=False)
    peer = SklearnLasso(alpha=alpha, fit_intercept=False, tol=1e-14, max_iter=100000)
    peer.fit(theta, y)
    ours = dc.Lasso(alpha=alpha).fit(theta, y).coef_
    np.testing.assert_allclose(ours, peer.coef_, atol=1e-7)
    np.testing.assert_array_equal(np.abs(ours) > 1e-9, np.abs(peer.coef_) > 1e-9)


def test_lasso_normalize_columns_equals_scikit_learn_on_scaled_columns():
    theta, y, _ = problem(5)
    norms = np.linalg.norm(theta, axis=0)
    peer = SklearnLasso(alpha=0.003, fit_intercept=False, tol=1e-14, max_iter=100000)
    peer.fit(theta / norms, y)
    ours = dc.Lasso(alpha=0.003, normalize_columns=True).fit(theta, y).coef_
    np.testing.assert_allclose(ours, peer.coef_ / norms, atol=1e-8)


def test_lasso_unbias_is_least_squares_on_the_support():
    theta, y, _ = problem(2, spread=False)
    support = dc.Lasso(alpha=0.05).fit(theta, y).coef_ != 0
    coef = dc.Lasso(alpha=0.05, unbias=True).fit(theta, y).coef_
    for i in range(y.shape[1]):
        s = support[i]
        ls = np.linalg.lstsq(theta[:, s], y[:, i], rcond=None)[0]
        np.testing.assert_allclose(coef[i, s], ls, rtol=1e-9, atol=1e-11)
        assert np.all(coef[i, ~s] == 0)


def test_lasso_alpha_zero_is_least_squares():
    theta, y, _ = problem(4, spread=False)
    ls = np.linalg.lstsq(theta, y, rcond=None)[0].T
    np.testing.assert_allclose(dc.Lasso(alpha=0.0).fit(theta, y).coef_, ls, rtol=1e-7,
                               atol=1e-9)


# ------------------------------------------------------------------- parameters

@pytest.mark.parametrize("optimizer, name", [(dc.STLSQ(threshold=-0.1), "threshold"),
                                             (dc.STLSQ(alpha=-1.0), "alpha"),
                                             (dc.STLSQ(threshold=float("nan")), "threshold"),
                                             (dc.STLSQ(max_iter=0), "max_iter"),
                                             (dc.Lasso(alpha=-1.0), "alpha")])
def test_bad_parameters_raise_at_fit(optimizer, name):
    theta, y, _ = problem(0)
    with pytest.raises(ParameterError, match=name):
        optimizer.fit(theta, y)


def test_not_fitted():
    with pytest.raises(NotFittedError):
        dc.STLSQ().check_is_fitted()


def test_fit_shape_errors():
    theta, y, _ = problem(0)
    with pytest.raises(ShapeError, match="y"):
        dc.STLSQ().fit(theta, y[:-1])
    with pytest.raises(ShapeError, match="gram"):
        dc.STLSQ().fit_gram(np.zeros((3, 4)), np.zeros((3, 1)))
    with pytest.raises(ShapeError, match="rhs"):
        dc.STLSQ().fit_gram(np.eye(3), np.zeros((4, 1)))


def test_all_coefficients_thresholded_away_warns_and_gives_zeros():
    theta, y, _ = problem(0)
    with pytest.warns(UserWarning, match="eliminated"):
        coef = dc.STLSQ(threshold=1e6).fit(theta, y).coef_
    assert np.all(coef == 0)


# ------------------------------------------------------------- Gram statistics

arrays = st.tuples(st.integers(1, 60), st.integers(1, 6), st.integers(1, 3),
                   st.integers(0, 2**16))


def _data(m, p, n, seed):
    rng = np.random.default_rng(seed)
    return rng.normal(size=(m, p)), rng.normal(size=(m, n))


@given(shape=arrays, cuts=st.lists(st.integers(0, 60), max_size=5))
def test_gram_chunks_equal_all_at_once(shape, cuts):
    theta, y = _data(*shape)
    m, p, n = theta.shape[0], theta.shape[1], y.shape[1]
    whole = dc.GramStatistics(p, n).add(theta, y)
    chunked = dc.GramStatistics(p, n)
    edges = [0, *sorted(c % (m + 1) for c in cuts), m]
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        chunked.add(theta[a:b], y[a:b])
    assert chunked.count == whole.count == m
    np.testing.assert_allclose(chunked.gram, theta.T @ theta, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(chunked.gram, whole.gram, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(chunked.rhs, theta.T @ y, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(chunked.yy, np.sum(y**2, axis=0), rtol=1e-12)


@given(shape=arrays, split=st.integers(0, 60))
def test_gram_merge_is_a_sum(shape, split):
    theta, y = _data(*shape)
    k = split % (theta.shape[0] + 1)
    p, n = theta.shape[1], y.shape[1]
    a = dc.GramStatistics(p, n).add(theta[:k], y[:k])
    b = dc.GramStatistics(p, n).add(theta[k:], y[k:])
    a_gram = a.gram.copy()
    merged = a.merge(b)
    np.testing.assert_allclose(merged.gram, a.gram + b.gram, rtol=1e-14)
    np.testing.assert_allclose(merged.gram, theta.T @ theta, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(merged.rhs, theta.T @ y, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(merged.yy, a.yy + b.yy, rtol=1e-14)
    assert merged.count == theta.shape[0]
    np.testing.assert_array_equal(a.gram, a_gram)  # merge does not modify its operands
    # merge is symmetric
    np.testing.assert_allclose(b.merge(a).rhs, merged.rhs, rtol=1e-14)


@given(shape=arrays)
def test_residual_sum_of_squares_from_statistics(shape):
    theta, y = _data(*shape)
    coef = np.random.default_rng(shape[3] + 1).normal(size=(y.shape[1], theta.shape[1]))
    stats = dc.GramStatistics(theta.shape[1], y.shape[1]).add(theta, y)
    direct = np.sum((y - theta @ coef.T) ** 2, axis=0)
    scale = np.sum(y**2, axis=0) + np.sum((theta @ coef.T) ** 2, axis=0)
    np.testing.assert_allclose(stats.residual_sum_of_squares(coef), direct,
                               atol=1e-10 * scale.max())


def test_gram_shape_errors():
    stats = dc.GramStatistics(3, 2)
    with pytest.raises(ShapeError):
        stats.add(np.zeros((4, 2)), np.zeros((4, 2)))
    with pytest.raises(ShapeError):
        stats.add(np.zeros((4, 3)), np.zeros((5, 2)))
    with pytest.raises(ShapeError):
        stats.merge(dc.GramStatistics(3, 1))


def test_refit_on_support_is_least_squares_of_each_target_on_its_own_terms():
    from discrepancy.optimizers.base import refit_on_support

    rng = np.random.default_rng(3)
    theta, y = rng.normal(size=(200, 5)), rng.normal(size=(200, 2))
    support = np.array([[True, False, True, True, False], [False, False, False, False, False]])
    coef = refit_on_support(theta.T @ theta, theta.T @ y, support)
    expected = np.linalg.lstsq(theta[:, support[0]], y[:, 0], rcond=None)[0]
    np.testing.assert_allclose(coef[0, support[0]], expected, rtol=1e-12)
    assert not coef[0, ~support[0]].any() and not coef[1].any()
    one = refit_on_support(theta.T @ theta, (theta.T @ y)[:, 0], support[0])
    np.testing.assert_array_equal(one, coef[0])
    ridge = refit_on_support(theta.T @ theta, theta.T @ y, support, alpha=10.0)[0, support[0]]
    a = theta[:, support[0]]
    np.testing.assert_allclose(ridge, np.linalg.solve(a.T @ a + 10.0 * np.eye(3), a.T @ y[:, 0]),
                               rtol=1e-12)
    # the minimum-norm solve: the same least squares and ridge as computed from the rows,
    # and on a rank-deficient support (a repeated column) the smallest coefficients, which
    # the Cholesky path does not promise
    plain, ridged = (refit_on_support(theta.T @ theta, theta.T @ y, support, alpha,
                                      minimum_norm=True)[0, support[0]] for alpha in (0.0, 10.0))
    np.testing.assert_allclose(plain, expected, rtol=1e-10)
    np.testing.assert_allclose(ridged, np.linalg.solve(a.T @ a + 10.0 * np.eye(3),
                                                       a.T @ y[:, 0]), rtol=1e-10)
    twice = np.c_[theta[:, :2], theta[:, :1]]             # column 0 twice
    both = refit_on_support(twice.T @ twice, twice.T @ y[:, 0], np.ones(3, bool),
                            minimum_norm=True)
    single = np.linalg.lstsq(theta[:, :2], y[:, 0], rcond=None)[0]
    np.testing.assert_allclose(both, [single[0] / 2, single[1], single[0] / 2], rtol=1e-8)


def test_the_hand_written_cholesky_gives_scipys_answers_and_refusals():
    """``solve_normal``'s Cholesky path answers every system as ``scipy.linalg.solve(...,
    assume_a="pos")`` does, to the last bit, and refuses exactly the systems scipy calls
    singular or warns about (random sizes 1-12, columns scaled over 16 decades, a third of
    them with two nearly equal columns)."""
    def by_scipy(a, b):
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("error", scipy.linalg.LinAlgWarning)
                return scipy.linalg.solve(a, b, assume_a="pos", check_finite=False)
        except (scipy.linalg.LinAlgError, scipy.linalg.LinAlgWarning):
            return None

    rng = np.random.default_rng(7)
    refused = answered = 0
    for _ in range(1500):
        p = int(rng.integers(1, 13))
        A = rng.normal(size=(int(rng.integers(1, 40)), p)) * 10.0 ** rng.uniform(-8, 8, p)
        if rng.random() < 0.35:
            A[:, -1] = A[:, 0] * (1 + 10.0 ** rng.uniform(-16, -4))
        d = np.sqrt(np.diag(A.T @ A))
        d[d == 0] = 1.0
        a = A.T @ A / np.outer(d, d)
        b = rng.normal(size=(p, 2)) if rng.random() < 0.5 else rng.normal(size=p)
        expected, got = by_scipy(a, b), _cholesky_solve(a, b)
        assert (expected is None) == (got is None)
        if got is None:
            refused += 1
        else:
            answered += 1
            assert got.shape == b.shape and np.array_equal(got, expected)
    assert refused > 300 and answered > 300        # both branches were exercised
