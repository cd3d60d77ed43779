"""Data validation: what as_trajectories accepts and how it normalises it."""
from __future__ import annotations

import numpy as np
import pytest

from discrepancy.data import Trajectory, as_trajectories
from discrepancy.data.trajectory import is_uniform
from discrepancy.errors import DataError, ShapeError


def test_single_array_with_a_step():
    x = np.arange(12, dtype=np.int64).reshape(6, 2)
    (tr,) = as_trajectories(x, t=0.5)
    assert isinstance(tr, Trajectory)
    assert tr.x.dtype == np.float64 and tr.x.shape == (6, 2)
    np.testing.assert_array_equal(tr.x, x)
    np.testing.assert_allclose(tr.t, [0, 0.5, 1.0, 1.5, 2.0, 2.5])
    assert tr.u is None and tr.x_dot is None and tr.n_samples == 6


def test_default_step_is_one():
    (tr,) = as_trajectories(np.zeros((4, 1)))
    np.testing.assert_array_equal(tr.t, [0, 1, 2, 3])


def test_times_are_kept_as_given():
    t = np.array([0.0, 0.1, 0.25, 0.7, 0.71])
    (tr,) = as_trajectories(np.zeros((5, 3)), t=t)
    np.testing.assert_array_equal(tr.t, t)
    assert tr.t.dtype == np.float64


def test_numpy_scalar_step():
    (tr,) = as_trajectories(np.zeros((3, 1)), t=np.float32(0.25))
    np.testing.assert_allclose(tr.t, [0, 0.25, 0.5])


def test_list_of_trajectories_shares_a_scalar_step():
    xs = [np.zeros((5, 2)), np.ones((8, 2))]
    trs = as_trajectories(xs, t=0.1)
    assert [tr.n_samples for tr in trs] == [5, 8]
    np.testing.assert_allclose(trs[1].t, np.arange(8) * 0.1)
    np.testing.assert_array_equal(trs[1].x, 1.0)


def test_list_of_trajectories_with_their_own_times_of_equal_length():
    ts = [np.linspace(0, 1, 5), np.linspace(3, 5, 5)]
    trs = as_trajectories([np.zeros((5, 1)), np.zeros((5, 1))], t=ts)
    np.testing.assert_array_equal(trs[1].t, ts[1])


def test_list_of_trajectories_with_their_own_times_of_different_lengths():
    ts = [np.linspace(0, 1, 5), np.linspace(3, 5, 9)]
    trs = as_trajectories([np.zeros((5, 1)), np.zeros((9, 1))], t=ts)
    np.testing.assert_array_equal(trs[1].t, ts[1])


def test_tuple_of_trajectories_and_list_of_steps():
    trs = as_trajectories((np.zeros((3, 1)), np.zeros((4, 1))), t=[0.1, 0.2])
    np.testing.assert_allclose(trs[0].t, [0, 0.1, 0.2])
    np.testing.assert_allclose(trs[1].t, [0, 0.2, 0.4, 0.6])


def test_one_dimensional_u_is_one_input_column():
    (tr,) = as_trajectories(np.zeros((4, 2)), t=1.0, u=np.arange(4))
    assert tr.u.shape == (4, 1) and tr.u.dtype == np.float64
    np.testing.assert_array_equal(tr.u[:, 0], [0, 1, 2, 3])


def test_inputs_and_derivatives_per_trajectory():
    xs = [np.zeros((3, 2)), np.zeros((5, 2))]
    us = [np.ones((3, 2)), 2 * np.ones((5, 2))]
    xds = [np.full((3, 2), 7.0), np.full((5, 2), 8.0)]
    trs = as_trajectories(xs, t=1.0, u=us, x_dot=xds)
    assert trs[1].u.shape == (5, 2) and np.all(trs[1].u == 2)
    assert np.all(trs[0].x_dot == 7) and np.all(trs[1].x_dot == 8)


def test_inputs_must_have_the_same_columns_in_every_trajectory():
    xs = [np.zeros((3, 2)), np.zeros((3, 2))]
    with pytest.raises(ShapeError, match=r"u\[1\]"):
        as_trajectories(xs, u=[np.zeros((3, 2)), np.zeros((3, 1))])


def test_arrays_are_not_shared_with_the_caller_in_a_way_that_changes_them():
    x = np.zeros((4, 2))
    as_trajectories(x, t=1.0)
    np.testing.assert_array_equal(x, 0.0)


def test_nested_lists_are_accepted_as_arrays():
    (tr,) = as_trajectories([[[0, 1], [2, 3], [4, 5]]], t=1.0)
    np.testing.assert_array_equal(tr.x, [[0, 1], [2, 3], [4, 5]])


def test_the_first_bad_value_is_located():
    x = np.zeros((10, 3))
    x[4, 2] = np.inf
    x[7, 0] = np.nan
    with pytest.raises(DataError, match=r"x must be finite; found inf at row 4, column 2 "
                                        r"\(2 non-finite values"):
        as_trajectories(x)


def test_times_that_repeat_are_refused():
    with pytest.raises(DataError, match=r"t\[2\] = 1.0 follows t\[1\] = 1.0"):
        as_trajectories(np.zeros((3, 1)), t=[0.0, 1.0, 1.0])


@pytest.mark.parametrize("t, expected", [
    (np.arange(10) * 0.1, True),
    (np.arange(10) * 0.1 + 1e6, True),            # large offsets, round-off in the steps
    (np.cumsum(np.full(1000, 1e-3)), True),       # accumulated steps
    (np.r_[0, 0.1, 0.2, 0.31, 0.4], False),
    (np.r_[0.0, 1.0, 3.0], False),
])
def test_is_uniform(t, expected):
    assert is_uniform(t) is expected
