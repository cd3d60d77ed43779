"""Limits: built by name, an actuator's saturation, and the verdict on a run."""
import numpy as np
import pytest

from discrepancy.control import Limits, Run
from discrepancy.errors import ParameterError, ShapeError


def run_of(x_dense, u, dt=0.1):
    """A Run whose dense states are ``x_dense`` ``(N, S+1, n)`` and inputs ``u`` ``(N, r)``."""
    x_dense = np.asarray(x_dense, float)
    N = len(u)
    t = np.arange(N + 1) * dt
    t_dense = t[:-1, None] + np.linspace(0, dt, x_dense.shape[1])[None, :]
    x = np.vstack([x_dense[:, 0], x_dense[-1, -1]])
    return Run(t=t, x=x, u=np.asarray(u, float), t_dense=t_dense, x_dense=x_dense)


def test_named_limits_place_bounds_by_name():
    lim = Limits.named(["phi", "s", "ds"], ["u"], states={"s": 0.5, "ds": (-1, 2)},
                       inputs={"u": 20}, rates={"u": 500})
    np.testing.assert_array_equal(lim.x_bounds, [[-np.inf, np.inf], [-0.5, 0.5], [-1, 2]])
    np.testing.assert_array_equal(lim.u_bounds, [[-20, 20]])
    np.testing.assert_array_equal(lim.du_max, [500])
    with pytest.raises(ParameterError, match=r"states names unknown variables \['rail'\]"):
        Limits.named(["phi", "s"], ["u"], states={"rail": 0.5})
    with pytest.raises(ParameterError, match="rates names unknown inputs"):
        Limits.named(["phi", "s"], ["u"], rates={"v": 1})
    with pytest.raises(ShapeError, match="x_bounds must be"):
        Limits(x_bounds=[[1, -1]])
    with pytest.raises(ShapeError, match="du_max must be"):
        Limits(du_max=[0.0])
    with pytest.raises(ShapeError, match=r"limits.u_bounds must be \(2, 2\)"):
        Limits(u_bounds=[[-1, 1]]).sized(3, 2)


def test_saturation_clips_to_bounds_and_to_the_rate_limit():
    lim = Limits(u_bounds=[[-2.0, 3.0]], du_max=[10.0])
    dt = 0.1  # at most 1.0 per step
    u, applied = 0.0, []
    for _ in range(5):
        u = lim.saturate([100.0], [u], dt)[0]
        applied.append(u)
    np.testing.assert_allclose(applied, [1.0, 2.0, 3.0, 3.0, 3.0])
    assert lim.saturate([-100.0], [-1.5], dt)[0] == -2.0   # bound before the rate
    assert Limits().saturate([7.0], [0.0], dt)[0] == 7.0    # no limits: unchanged


def test_check_measures_every_excess_on_the_dense_states_and_inputs():
    lim = Limits(x_bounds=[[-0.5, 0.5]], u_bounds=[[-1, 1]], du_max=[5.0])
    x = np.array([[[0.0], [0.3], [0.52]], [[0.52], [0.4], [0.1]]])  # 0.52 between grid points
    report = lim.check(run_of(x, [[0.5], [1.0]]))
    assert report["max_state_excess"] == pytest.approx(0.02)
    assert not report["within_state_bounds"] and not report["respected"]
    assert report["within_input_bounds"]
    assert report["max_rate_ratio"] == pytest.approx(1.0)   # 0.5/0.1 from u = 0 before
    ok = lim.check(run_of(x * 0.9, [[0.5], [1.0]]))
    assert ok["respected"] and ok["max_state_excess"] == 0.0
    too_fast = lim.check(run_of(x * 0.9, [[0.5], [-0.5]]))
    assert too_fast["max_rate_ratio"] == pytest.approx(2.0) and not too_fast["respected"]
