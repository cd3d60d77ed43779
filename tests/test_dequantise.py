"""Dequantised: reconstruction of encoder readings before differentiation.

Ground truth: analytic signals (positions and speeds known exactly) read through a
simulated encoder.
"""
import numpy as np
import pytest

import discrepancy as dc
from discrepancy.errors import DataError, ParameterError, ShapeError

STEP = 2 * np.pi / 5000


def _encoder(y, step=STEP):
    return np.round(y / step) * step


def _slow_swing():
    """A decaying swing whose speed passes slowly through whole counts per sample."""
    t = np.arange(20001) / 1000.0
    amp = 0.4 * np.exp(-t / 30)
    w = 2 * np.pi * 0.9
    y = amp * np.sin(w * t)
    dy = amp * (w * np.cos(w * t) - np.sin(w * t) / 30)
    return t, y[:, None], dy[:, None]


def _rms(a, b, edge):
    return float(np.sqrt(np.mean((a[edge:-edge] - b[edge:-edge]) ** 2)))


def test_reconstruction_beats_smoothing_alone_on_quantised_positions_and_speeds():
    t, y, dy = _slow_swing()
    q = _encoder(y)
    sg = dc.SavitzkyGolay(71, 6)
    deq = dc.Dequantised(sg, resolution=STEP)
    y_sg, dy_sg = sg.smooth_and_differentiate(q, t)
    y_dq, dy_dq = deq.smooth_and_differentiate(q, t)
    edge = deq.edge
    assert _rms(y_dq, y, edge) < 0.7 * _rms(y_sg, y, edge)
    assert _rms(dy_dq, dy, edge) < 0.7 * _rms(dy_sg, dy, edge)


def test_relative_encoder_matrix():
    """Encoders on phi1 and phi2 - phi1: reconstruction in encoder coordinates."""
    t, y, dy = _slow_swing()
    phi1, phi2 = y[:, 0], 1.7 * y[:, 0] + 0.05 * np.sin(3.1 * t)
    rel = _encoder(phi2 - phi1)
    q = np.column_stack([_encoder(phi1), _encoder(phi1) + rel])
    exact = np.column_stack([phi1, phi2])
    deq = dc.Dequantised(resolution=STEP, encoders=[[1, 0], [-1, 1]])
    q_dq, _ = deq.smooth_and_differentiate(q, t)
    q_sg, _ = dc.SavitzkyGolay(71, 6).smooth_and_differentiate(q, t)
    assert _rms(q_dq, exact, deq.edge) < 0.7 * _rms(q_sg, exact, deq.edge)
    # the identity matrix does not fit these readings: phi2 is not on the grid by itself
    with pytest.raises(DataError, match="encoder 1 is not quantised"):
        dc.Dequantised(resolution=STEP)(q + np.array([0, 0.3 * STEP]), t)


def test_smooth_unquantised_signal_is_refused_not_silently_passed():
    t, y, _ = _slow_swing()
    with pytest.raises(DataError, match="resolution"):
        dc.Dequantised(resolution=STEP)(y, t)


@pytest.mark.parametrize("kwargs, error, text", [
    ({"resolution": 0.0}, ParameterError, "resolution must be > 0"),
    ({"resolution": [STEP, STEP, STEP]}, ParameterError, "one per encoder"),
    ({"resolution": "fine"}, ParameterError, "resolution must be > 0"),
    ({"resolution": STEP, "encoders": [[1, 0, 0]]}, ShapeError, "encoders must be an"),
    ({"resolution": STEP, "encoders": [[1, 1], [1, 1]]}, ParameterError, "invertible"),
    ({"resolution": STEP, "iterations": 0}, ParameterError, "iterations"),
])
def test_bad_arguments_name_themselves(kwargs, error, text):
    t = np.arange(400) / 1000.0
    q = _encoder(np.column_stack([np.sin(t), np.cos(t)]))
    with pytest.raises(error, match=text):
        dc.Dequantised(**kwargs)(q, t)


def test_global_method_has_no_halo_but_an_edge():
    deq = dc.Dequantised(dc.SavitzkyGolay(31, 3), resolution=STEP, window_length=101)
    assert deq.halo is None          # streaming refuses it instead of stitching wrongly
    assert deq.edge == 50
    assert deq.min_samples == 101
