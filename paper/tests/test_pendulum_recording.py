"""Loader of the measured free swing: joins segments, refuses inconsistent or implausible files."""
import numpy as np
import pytest
from scipy.io import savemat

from discrepancy.errors import DataError, ShapeError
from discrepancy_paper.datasets import data_file
from discrepancy_paper.experiments.pendulum_energy_measured import RECORDING
from discrepancy_paper.recording import load_pendulum_recording


def _cells(arrays):
    cell = np.empty((len(arrays), 1), dtype=object)
    for i, a in enumerate(arrays):
        cell[i, 0] = a
    return cell


def _recording(n_id=(50, 50), n_vad=(40,), dt=0.001, degrees=False, t_steps=None):
    """A swing sampled every dt, cut like the rig's file; returns the dict and the full angles."""
    n = sum(n_id) + sum(n_vad)
    t = np.arange(n) * dt
    angles = np.column_stack([np.pi + 0.3 * np.sin(3 * t), np.pi + 0.5 * np.sin(5 * t + 1)])
    if degrees:
        angles = np.rad2deg(angles)
    y = np.vstack([angles.T, np.zeros((2, n))])
    stamps = t if t_steps is None else np.concatenate([[0], np.cumsum(t_steps)])
    parts, times, start = [], [], 0
    for size in (*n_id, *n_vad):
        parts.append(y[:, start:start + size])
        times.append(stamps[start:start + size, None])
        start += size
    k = len(n_id)
    return {"dt": np.array([[dt]]), "Y_id": _cells(parts[:k]), "Y_vad": _cells(parts[k:]),
            "Time_id": _cells(times[:k]), "Time_vad": _cells(times[k:])}, angles


def test_segments_join_in_order(tmp_path):
    contents, angles = _recording()
    savemat(tmp_path / "rec.mat", contents)
    rec = load_pendulum_recording(tmp_path / "rec.mat")
    np.testing.assert_array_equal(rec.angles, angles)
    np.testing.assert_allclose(rec.t, np.arange(140) * 0.001)
    assert rec.split_index == 100
    assert rec.split_time == pytest.approx(0.1)


def test_missing_variables_are_named(tmp_path):
    contents, _ = _recording()
    del contents["Y_vad"]
    savemat(tmp_path / "rec.mat", contents)
    with pytest.raises(DataError, match=r"lacks variable\(s\) \['Y_vad'\]"):
        load_pendulum_recording(tmp_path / "rec.mat")


def test_segment_and_time_lengths_must_match(tmp_path):
    contents, _ = _recording()
    contents["Time_id"][1, 0] = contents["Time_id"][1, 0][:-5]
    savemat(tmp_path / "rec.mat", contents)
    with pytest.raises(ShapeError, match="Time_id\\[1\\] has 45 times but Y_id\\[1\\] has 50"):
        load_pendulum_recording(tmp_path / "rec.mat")


def test_segments_must_be_4_rows(tmp_path):
    contents, _ = _recording()
    contents["Y_vad"][0, 0] = contents["Y_vad"][0, 0][:3]
    savemat(tmp_path / "rec.mat", contents)
    with pytest.raises(ShapeError, match="4 x N"):
        load_pendulum_recording(tmp_path / "rec.mat")


def test_other_sampling_rate_in_a_segment_is_refused(tmp_path):
    steps = np.full(139, 0.001)
    steps[100:] = 0.002                     # the validation segment sampled at 500 Hz
    contents, _ = _recording(t_steps=steps)
    savemat(tmp_path / "rec.mat", contents)
    with pytest.raises(DataError, match="same sampling rate"):
        load_pendulum_recording(tmp_path / "rec.mat")


def test_angles_in_degrees_are_detected(tmp_path):
    contents, _ = _recording(degrees=True)
    savemat(tmp_path / "rec.mat", contents)
    with pytest.raises(DataError, match="degrees"):
        load_pendulum_recording(tmp_path / "rec.mat")


def test_wrapped_angles_are_detected(tmp_path):
    contents, _ = _recording()
    contents["Y_id"][1, 0][0, 10:] -= 2 * np.pi
    savemat(tmp_path / "rec.mat", contents)
    with pytest.raises(DataError, match="unwrap"):
        load_pendulum_recording(tmp_path / "rec.mat")


def test_missing_and_unreadable_files(tmp_path):
    with pytest.raises(DataError, match="does not exist"):
        load_pendulum_recording(tmp_path / "nothing.mat")
    (tmp_path / "text.mat").write_text("not a mat file")
    with pytest.raises(DataError, match="MATLAB"):
        load_pendulum_recording(tmp_path / "text.mat")


def test_real_recording_is_one_80_s_swing():
    rec = load_pendulum_recording(data_file("double_pendulum", RECORDING))
    assert rec.angles.shape == (80001, 2)
    assert rec.t[-1] == pytest.approx(80.0)
    assert rec.split_time == pytest.approx(69.342)
    # settles hanging down (pi) and the filtered stored velocities lag the raw angles
    assert np.all(np.abs(rec.angles[-1000:] - np.pi) < 0.5)
    fd = np.gradient(rec.angles[:, 0], rec.dt)
    lags = range(0, 30)
    corr = [np.corrcoef(fd[:-40], rec.stored_velocities[lag:len(fd) - 40 + lag, 0])[0, 1]
            for lag in lags]
    assert int(np.argmax(corr)) > 0
