"""Fields on grids: the same clear errors as for trajectories, naming the argument, run,
time row and grid point."""
import numpy as np
import pytest

from discrepancy import Grid
from discrepancy.data.fields import as_field_runs
from discrepancy.errors import DataError, ParameterError, ShapeError

X = np.linspace(0, 1, 16, endpoint=False)
Y = np.linspace(0, 2, 8, endpoint=False)


def test_grid_describes_uniform_periodic_axes():
    g = Grid(X, Y, periodic=(True, False))
    assert g.shape == (16, 8) and g.size == 128 and g.names == ("x", "y")
    assert g.spacing == pytest.approx((1 / 16, 2 / 8))
    assert g.period[0] == pytest.approx(1.0)
    assert g.mesh()[1].shape == (16, 8)
    assert Grid(X) == Grid(X.copy()) and Grid(X) != Grid(X, periodic=True)


@pytest.mark.parametrize("args, kwargs, error, words", [
    ((np.r_[0, 1, 3.0],), {}, DataError, "equally spaced"),
    ((np.r_[0, 2, 1.0],), {}, DataError, "strictly increasing"),
    ((np.r_[0, np.nan, 1.0],), {}, DataError, "finite"),
    ((np.zeros((3, 3)),), {}, ShapeError, "1-D"),
    ((X,), {"periodic": "yes"}, ParameterError, "periodic"),
    ((X, Y), {"periodic": (True,)}, ParameterError, "one bool per axis"),
    ((X,), {"names": ("xx",)}, ParameterError, "single lowercase"),
    ((X,), {"names": ("t",)}, ParameterError, "other than 't'"),
    ((), {}, ShapeError, "1 to 3"),
])
def test_bad_grids_are_refused_by_name(args, kwargs, error, words):
    with pytest.raises(error, match=words):
        Grid(*args, **kwargs)


def test_one_field_gets_a_field_axis_and_signals_are_broadcast():
    g = Grid(X)
    run, = as_field_runs(np.ones((5, 16)), 0.1, g, inputs=np.arange(5.0))
    assert run.u.shape == (5, 16, 1) and run.inputs.shape == (5, 16, 1)
    assert np.array_equal(run.inputs[:, 3, 0], np.arange(5.0))
    assert run.t[-1] == pytest.approx(0.4)
    two = as_field_runs([np.ones((5, 16, 2)), np.ones((7, 16, 2))], [0.1, 0.2], g)
    assert [r.n_samples for r in two] == [5, 7] and two[1].t[1] == pytest.approx(0.2)


@pytest.mark.parametrize("u, t, inputs, error, words", [
    (np.ones((5, 15)), 0.1, None, ShapeError, r"u must be \(time, 16\)"),
    (np.ones((5, 16, 0)), 0.1, None, ShapeError, "u must be"),
    (np.ones((2, 16)), 0.1, None, ShapeError, "at least 3 time samples"),
    ("text", 0.1, None, ShapeError, "numeric"),
    (np.ones((5, 16)) + 1j, 0.1, None, DataError, "real"),
    (np.where(np.arange(80).reshape(5, 16) == 37, np.nan, 1.0), 0.1, None, DataError,
     r"time row 2, grid point \(5,\)"),
    (np.ones((5, 16)), -1.0, None, DataError, "positive"),
    (np.ones((5, 16)), np.r_[0, 1, 2, 4, 5.0], None, DataError, "equally spaced"),
    (np.ones((5, 16)), np.r_[0, 1, 1, 2, 3.0], None, DataError, "strictly increasing"),
    (np.ones((5, 16)), 0.1, np.ones((4, 16)), ShapeError, "5 time rows"),
    ([np.ones((5, 16)), np.ones((5, 16, 2))], 0.1, None, ShapeError, r"u\[1\] must hold 1"),
    ([np.ones((5, 16))] * 2, [0.1], None, ShapeError, "list of 2"),
    ([np.ones((5, 16))] * 2, np.arange(5.0), None, ShapeError, "list of 2 items"),
    ([], 0.1, None, ShapeError, "at least one run"),
    ([np.ones((5, 16))] * 2, 0.1, [np.ones(5), None], ShapeError, "all runs or none"),
])
def test_bad_fields_are_refused_by_name(u, t, inputs, error, words):
    with pytest.raises(error, match=words):
        as_field_runs(u, t, Grid(X), inputs)


def test_grid_must_be_a_grid():
    with pytest.raises(ParameterError, match="grid must be a discrepancy.Grid"):
        as_field_runs(np.ones((5, 16)), 0.1, X)
