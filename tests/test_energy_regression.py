"""Non-negative least squares under linear inequality constraints, against scipy's SLSQP
on the same problems, and the statistics of the cumulative and block fits against direct
least squares on the samples."""
import numpy as np
import pytest
from scipy.optimize import lsq_linear, minimize

from discrepancy.energy.regression import (
    block_statistics,
    cumulative_statistics,
    nonnegative_fit,
    solve_constrained,
)


def slsqp(gram, rhs, rows, bounds):
    constraints = [{"type": "ineq", "fun": lambda x: bounds - rows @ x, "jac": lambda x: -rows}]
    return minimize(lambda x: 0.5 * x @ gram @ x - rhs @ x, np.zeros(len(rhs)),
                    jac=lambda x: gram @ x - rhs, bounds=[(0, None)] * len(rhs),
                    constraints=constraints if len(rows) else (), method="SLSQP",
                    options={"ftol": 1e-15, "maxiter": 1000}).x


@pytest.mark.parametrize("seed", range(40))
def test_constrained_solution_is_feasible_and_as_good_as_slsqp(seed):
    rng = np.random.default_rng(seed)
    k = int(rng.integers(1, 7))
    design = rng.normal(size=(60, k))
    design[:, 0] += 3 * design[:, -1]                  # correlated columns
    target = design @ rng.uniform(-1, 2, k) + 0.1 * rng.normal(size=60)
    gram, rhs = design.T @ design, design.T @ target
    rows = rng.uniform(0, 1, (int(rng.integers(0, 200)), k))
    bounds = rng.uniform(0.05, 1, len(rows))
    xi = solve_constrained(gram, rhs, rows, bounds)
    assert np.all(xi >= 0) and np.all(rows @ xi <= bounds * (1 + 1e-9))
    ref = np.maximum(slsqp(gram, rhs, rows, bounds), 0.0)
    ref /= max(1.0, float(np.max(rows @ ref / bounds, initial=0.0)))   # SLSQP's 1e-8 excess
    objective = lambda x: 0.5 * x @ gram @ x - rhs @ x     # noqa: E731
    assert objective(xi) <= objective(ref) + 1e-8 * (1 + abs(objective(ref)))


def test_cumulative_fit_equals_bounded_least_squares_with_an_offset():
    rng = np.random.default_rng(3)
    features = np.cumsum(rng.uniform(0, 1, (500, 3)), axis=0)
    target = 0.7 + features @ [0.2, 0.0, 0.05] + 0.5 * rng.normal(size=500)
    coef = nonnegative_fit(features, target)
    ref = lsq_linear(np.column_stack([np.ones(500), features]), target,
                     bounds=([-np.inf, 0, 0, 0], np.inf), method="bvls", tol=1e-14).x
    np.testing.assert_allclose(coef, ref, rtol=1e-7, atol=1e-9)
    stats = cumulative_statistics(features, target)
    xi, loss = stats.fit([0, 2])
    residual = target - stats.offset([0, 2], xi) - features[:, [0, 2]] @ xi
    assert loss == pytest.approx(residual @ residual, rel=1e-9)


def test_block_statistics_fit_the_weighted_losses_between_block_means():
    rng = np.random.default_rng(4)
    features = np.cumsum(rng.uniform(0, 1, (400, 2)), axis=0)
    target = features @ [0.3, 0.1] + 0.01 * rng.normal(size=400)
    stats = block_statistics(features, target, 40)
    means = lambda v: v.reshape(10, 40, *v.shape[1:]).mean(axis=1)   # noqa: E731
    loss, gained = np.diff(means(target)), np.diff(means(features), axis=0)
    w = 1 / np.abs(loss)
    ref = lsq_linear(gained * w[:, None], loss * w, bounds=(0, np.inf), tol=1e-14).x
    np.testing.assert_allclose(stats.fit([0, 1])[0], ref, rtol=1e-7)
