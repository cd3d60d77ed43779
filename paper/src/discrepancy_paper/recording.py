"""Loader for the measured free swing of the mounted double pendulum (MATLAB file).

The file (MultiArm-Pendulum rig, ``DoublePendulumDataForParameterEstimation.mat``)
stores one 80 s recording at 1 kHz cut into cells: ``Y_id`` (identification) then
``Y_vad`` (validation), each cell ``4 x N`` = ``[theta1; theta2; dtheta1; dtheta2]``
with absolute angles in rad (``pi`` hangs down), times in ``Time_id``/``Time_vad`` and
the step in ``dt``. The stored velocities were median- and wavelet-filtered and lag
the angles, so they are kept only for comparison; differentiate the raw angles.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from discrepancy.errors import DataError, ShapeError

# Plausibility limits for a pendulum recorded in radians.
MAX_ABS_ANGLE = 20 * np.pi      # ten full turns from upright; degrees (~180 at rest) exceed it
MAX_ANGULAR_SPEED = 200.0       # rad/s between two samples; wrapped or degree data exceed it


@dataclass(frozen=True)
class PendulumRecording:
    """One contiguous recording.

    Attributes:
        t: times (s), shape ``(m,)``, uniform step ``dt``.
        angles: ``[theta1, theta2]`` (rad), shape ``(m, 2)``, raw (not filtered).
        stored_velocities: the file's filtered velocities (rad/s), shape ``(m, 2)``.
        dt: sampling step (s).
        split_index: first sample of the validation part (``Y_vad``).
    """

    t: np.ndarray
    angles: np.ndarray
    stored_velocities: np.ndarray
    dt: float
    split_index: int

    @property
    def split_time(self) -> float:
        """Time (s) at which the validation part starts."""
        return float(self.t[self.split_index])


def _cells(contents: dict, name: str, path: str) -> list[np.ndarray]:
    value = contents[name]
    if value.dtype != object:
        return [np.asarray(value, dtype=float)]
    return [np.asarray(c, dtype=float) for c in value.ravel()]


def _require(contents: dict, names, path: str) -> None:
    missing = [n for n in names if n not in contents]
    if missing:
        found = sorted(k for k in contents if not k.startswith("__"))
        raise DataError(f"{path!r} lacks variable(s) {missing}; it holds {found}. Expected "
                        "Y_id and Y_vad (cells of 4 x N [theta1; theta2; dtheta1; dtheta2]) and dt")


def load_pendulum_recording(path, *, segments=("Y_id", "Y_vad"), times=("Time_id", "Time_vad"),
                            dt_name: str = "dt") -> PendulumRecording:
    """Join the segments of a measured free swing into one recording.

    Args:
        path: the ``.mat`` file.
        segments: names of the cell arrays, joined in this order; the first is the
            identification part, the rest validation.
        times: names of the matching time cells (checked when present in the file).
        dt_name: name of the sampling step (s).

    Raises:
        DataError: missing file or variables, inconsistent sampling, implausible angles
            (e.g. degrees instead of radians, or wrapped angles).
        ShapeError: a segment that is not ``4 x N`` or whose time cell has another length.
        DataError: the file is missing or not a readable MATLAB file.
    """
    from discrepancy.data.io import read_mat

    where = str(path)
    contents = read_mat(path, what="recording")
    _require(contents, [*segments, dt_name], where)
    dt = np.asarray(contents[dt_name], dtype=float).ravel()
    if dt.size != 1 or not np.isfinite(dt[0]) or dt[0] <= 0:
        raise DataError(f"{dt_name} in {where!r} must be one positive step (s); got {dt}")
    dt = float(dt[0])
    pieces, stamps = [], []
    for s_name, t_name in zip(segments, times, strict=True):
        cells = _cells(contents, s_name, where)
        stamp_cells = _cells(contents, t_name, where) if t_name in contents else None
        if stamp_cells is not None and len(stamp_cells) != len(cells):
            raise ShapeError(f"{s_name} has {len(cells)} segments but {t_name} has "
                             f"{len(stamp_cells)}; they must match one to one")
        for i, cell in enumerate(cells):
            if cell.ndim != 2 or cell.shape[0] != 4:
                raise ShapeError(f"{s_name}[{i}] must be 4 x N [theta1; theta2; dtheta1; "
                                 f"dtheta2]; got shape {cell.shape}")
            pieces.append(cell.T)
            if stamp_cells is not None:
                stamp = stamp_cells[i].ravel()
                if stamp.shape[0] != cell.shape[1]:
                    raise ShapeError(f"{t_name}[{i}] has {stamp.shape[0]} times but {s_name}[{i}] "
                                     f"has {cell.shape[1]} samples; segment lengths must match")
                stamps.append(stamp)
        if s_name == segments[0]:
            split_index = sum(p.shape[0] for p in pieces)
    if stamps and len(stamps) != len(pieces):
        raise DataError(f"some segments of {where!r} have time cells and others not")
    data = np.vstack(pieces)
    t = np.concatenate(stamps) if stamps else np.arange(data.shape[0]) * dt
    _check_sampling(t, dt, where)
    _check_angles(data[:, :2], dt, where)
    if not np.all(np.isfinite(data)):
        raise DataError(f"{where!r} holds {np.count_nonzero(~np.isfinite(data))} non-finite values")
    return PendulumRecording(t=t - t[0], angles=data[:, :2].copy(),
                             stored_velocities=data[:, 2:].copy(), dt=dt, split_index=split_index)


def _check_sampling(t: np.ndarray, dt: float, where: str) -> None:
    steps = np.diff(t)
    bad = np.flatnonzero(np.abs(steps - dt) > 1e-6 * max(dt, 1.0) + 1e-3 * dt)
    if bad.size:
        i = int(bad[0])
        raise DataError(f"the segments of {where!r} are not one recording sampled every "
                        f"dt = {dt:g} s: the step from t = {t[i]:.6g} s to {t[i + 1]:.6g} s is "
                        f"{steps[i]:.6g} s ({bad.size} such steps); segments must have the same "
                        "sampling rate and follow each other without gaps")


def _check_angles(angles: np.ndarray, dt: float, where: str) -> None:
    if not np.all(np.isfinite(angles)):
        raise DataError(f"angles in {where!r} contain non-finite values")
    peak = float(np.max(np.abs(angles)))
    if peak > MAX_ABS_ANGLE:
        raise DataError(f"angles in {where!r} reach |theta| = {peak:.4g}, implausible in radians "
                        f"(limit {MAX_ABS_ANGLE:.4g} rad = ten turns); they look like degrees "
                        "(hanging down would read 180). Convert with numpy.deg2rad")
    speed = float(np.max(np.abs(np.diff(angles, axis=0)))) / dt
    if speed > MAX_ANGULAR_SPEED:
        raise DataError(f"angles in {where!r} jump by {speed * dt:.4g} between two samples "
                        f"({speed:.4g} rad/s > {MAX_ANGULAR_SPEED:g} rad/s): angles in degrees or "
                        "wrapped to [-pi, pi) (use numpy.unwrap)?")
