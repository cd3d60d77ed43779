"""Differentiate encoder readings after undoing their quantisation.

An incremental encoder of resolution ``s`` reports ``round(y / s) * s``: the true ``y`` lies in
the cell ``[reading - s/2, reading + s/2]``, and the quantisation error is a deterministic
function of ``y``, not noise. Whenever a joint turns by close to a whole number of counts per
sample the error stays nearly constant over many samples, so a smoothing differentiator alone
passes it as a slow, systematic error in positions and velocities.

:class:`Dequantised` first finds a smooth signal that is *consistent* with every reading
(alternating projections: smooth with a Savitzky-Golay filter, then clip each sample back into
its cell), then differentiates that signal with another method. Written by hand: no library we
use reconstructs quantised signals. ``benchmarks/bench_dequantise.py`` measures what it does to
the friction coefficients of the pendulum-energy experiment on 50 seeds the experiment does
not use.
"""
from __future__ import annotations

import numpy as np

from ..constraints import InstanceOf, Integral, Interval
from ..data.validation import as_float_array
from ..errors import DataError, ParameterError, ShapeError
from .base import Differentiator, register
from .methods import MAX_POLYORDER, ODD_WINDOW, SavitzkyGolay


@register("dequantised")
class Dequantised(Differentiator):
    """Consistent reconstruction of quantised positions, then differentiation.

    Args:
        method: the differentiator applied to the reconstructed signal
            (default ``SavitzkyGolay(window_length=71, polyorder=6)``).
        resolution: encoder step in the units of ``x`` (e.g. ``2 pi / 5000`` rad for 5000
            counts per revolution); a scalar or one value per encoder.
        encoders: ``(n, n)`` invertible matrix ``E``: the encoders read ``x @ E.T``. Default:
            the identity (one encoder per column). A double pendulum with encoders on
            ``phi1`` and on the relative angle ``phi2 - phi1`` has ``E = [[1, 0], [-1, 1]]``.
        window_length, polyorder: Savitzky-Golay smoother of the reconstruction (samples).
        iterations: number of smooth-and-clip passes.

    Needs uniform ``t``. The readings must lie on the encoder grid (checked: a wrong
    ``resolution`` or ``encoders`` is an error, not a silent no-op). Global method (each sample
    depends on the whole record), so it cannot be applied chunk by chunk.
    """

    uniform_only = True
    _parameter_constraints = {
        "method": [None, InstanceOf(Differentiator, "a Differentiator")],
        "window_length": [ODD_WINDOW], "polyorder": [Interval(Integral, 1, MAX_POLYORDER)],
        "iterations": [Interval(Integral, 1, None)]}

    def __init__(self, method: Differentiator | None = None, *, resolution, encoders=None,
                 window_length: int = 101, polyorder: int = 6, iterations: int = 30):
        self.method = method
        self.resolution = resolution
        self.encoders = encoders
        self.window_length = window_length
        self.polyorder = polyorder
        self.iterations = iterations

    @property
    def _inner(self) -> Differentiator:
        return SavitzkyGolay(71, 6) if self.method is None else self.method

    @property
    def _smoother(self) -> SavitzkyGolay:
        return SavitzkyGolay(self.window_length, self.polyorder)

    @property
    def min_samples(self) -> int:
        return max(self._inner.min_samples, self._smoother.min_samples)

    @property
    def edge(self) -> int:
        return max(self._inner.edge, self.window_length // 2)

    def _matrix(self, n: int) -> np.ndarray:
        if self.encoders is None:
            return np.eye(n)
        e = as_float_array("encoders", self.encoders)
        if e.shape != (n, n):
            raise ShapeError(f"encoders must be an ({n}, {n}) matrix for x with {n} columns; "
                             f"got shape {e.shape}")
        if not np.all(np.isfinite(e)) or abs(np.linalg.det(e)) < 1e-12:
            raise ParameterError(f"encoders must be a finite, invertible matrix; got {e.tolist()}")
        return e

    def _steps(self, n: int) -> np.ndarray:
        try:
            steps = np.asarray(self.resolution, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            steps = np.array([np.nan])
        if steps.size == 1:
            steps = np.repeat(steps, n)
        if steps.shape != (n,) or not np.all(np.isfinite(steps)) or np.any(steps <= 0):
            raise ParameterError(f"resolution must be > 0, a scalar or {n} values (one per "
                                 f"encoder); got {self.resolution!r}")
        return steps

    def _compute(self, x, t):
        e = self._matrix(x.shape[1])
        step = self._steps(x.shape[1])
        readings = x @ e.T
        counts = readings / step
        off_grid = np.max(np.abs(counts - np.round(counts)), axis=0)
        if np.any(off_grid > 1e-3):
            j = int(np.argmax(off_grid))
            raise DataError(f"encoder {j} is not quantised with resolution {step[j]:.6g}: its "
                            f"readings are up to {off_grid[j]:.3g} counts off the grid; check "
                            "resolution and encoders (or use the differentiator without "
                            "Dequantised for data that are not quantised)")
        low, high = readings - step / 2, readings + step / 2
        y, smoother = readings, self._smoother
        for _ in range(self.iterations):
            y = np.clip(smoother.smooth_and_differentiate(y, t)[0], low, high)
        return self._inner.smooth_and_differentiate(np.linalg.solve(e, y.T).T, t)
