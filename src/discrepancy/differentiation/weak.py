"""The weak (integral) form: no pointwise derivative at all.

For a smooth test function ``φ`` that vanishes, with its derivative, at both ends of a
window of ``L`` samples, integration by parts turns ``dx/dt = f_m(x, u) + Θ(x, u) ξ`` into

    -∫ φ' x dt - ∫ φ f_m(x, u) dt = (∫ φ Θ(x, u) dt) ξ,

which involves the measured states only, never their derivative. One such equation is
formed per sample (the window centred on it: a convolution of ``x``, ``f_m`` and every
library column with ``φ`` or ``φ'``), so the regression, the cross-validation and the
streaming code see rows as for the pointwise form, and a row depends on ``L // 2`` samples
each side (the ``halo`` that chunked fits stitch over). Rows whose window leaves the
trajectory are zero (they add nothing to the sums). ``φ(τ) = (1 - τ²)^q`` on
``τ ∈ [-1, 1]``; integrals by the rectangle rule, accurate to ``O(h^(2q+1))`` for such
``φ`` once a window spans a few dozen samples. Written here because no library we use
provides it (PySINDy's ``WeakPDELibrary`` integrates over random sub-domains of one
trajectory and is not a Gram-statistics operator).
"""
from __future__ import annotations

import numpy as np

from ..constraints import Integral, Interval
from ..data.validation import is_uniform
from ..errors import DataError, ParameterError, ShapeError
from .base import Differentiator, register
from .methods import ODD_WINDOW


@register("weak")
class WeakForm(Differentiator):
    """Integral form of the regression over windows of ``window_length`` samples.

    Args:
        window_length: odd number of samples of each test function's support (default: a
            multiple of the window that GCV finds for smoothing the states, at least 31:
            chosen from the data at each fit, like ``"auto"``).
        power: ``q`` of the test function ``(1 - τ²)^q`` (>= 2: zero slope at the ends;
            the default 8 makes the rectangle rule exact to ~1e-10 on smooth data, where 4
            left quadrature errors that the selection took for terms).

    Needs uniform ``t``. The library is evaluated on the measured states (no smoothing),
    so the remaining error at high noise is the bias of nonlinear terms of noisy states.
    """

    uniform_only = True
    _parameter_constraints = {"window_length": [None, ODD_WINDOW],
                              "power": [Interval(Integral, 2, 12)]}

    def __init__(self, window_length: int | None = None, *, power: int = 8):
        self.window_length = window_length
        self.power = power

    @property
    def data_driven(self) -> bool:
        """True when the window is chosen from the data at each fit (``window_length=None``)."""
        return self.window_length is None

    @property
    def sample_rows(self) -> int:
        """Rows the automatic window is chosen from (those of ``"auto"``), also when streamed."""
        from .auto import AutoSmoothing

        return AutoSmoothing().sample_rows

    def choose(self, series) -> tuple[WeakForm, dict]:
        """A weak form with the window chosen from data ``series`` (list of ``(t, x)``)."""
        from .auto import AutoSmoothing

        method, info = AutoSmoothing().choose(series)
        if not isinstance(method, Differentiator) or not hasattr(method, "window_length"):
            return method, info  # non-uniform times: the smoothing spline, as "auto"
        window = max(MIN_WINDOW, int(max(info["gcv_window"]) * WINDOW_SCALE) // 2 * 2 + 1)
        info = {**info, "chosen_by": "GCV (weak form)", "window_length": window}
        return WeakForm(window, power=self.power), info

    @property
    def min_samples(self) -> int:
        self._validate_params()
        return int(self.window_length or MIN_WINDOW)

    @property
    def halo(self) -> int | None:
        return None if self.window_length is None else int(self.window_length) // 2

    def kernels(self, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """``(φ w, φ' w)`` ``(L,)``: the test function and its derivative times the
        quadrature weight ``dt``, as correlation weights over the window."""
        L = int(self.window_length)
        tau = np.linspace(-1.0, 1.0, L)
        half = (L - 1) * dt / 2
        q = self.power
        phi = (1 - tau ** 2) ** q
        dphi = -2 * q * tau * (1 - tau ** 2) ** (q - 1) / half
        return phi * dt, dphi * dt

    def rows(self, x, t, values) -> tuple[np.ndarray, np.ndarray]:
        """``(∫ φ values, -∫ φ' x)`` per sample: ``(m, k)`` and ``(m, n)``; rows whose
        window leaves the data are zero."""
        from scipy.signal import oaconvolve

        self._validate_params()
        if len(x) < self.window_length:
            raise ShapeError(f"WeakForm: window_length {self.window_length} is longer than a "
                             f"trajectory of {len(x)} samples; give a shorter window_length "
                             "or longer trajectories")
        if not is_uniform(t):
            raise DataError("WeakForm needs uniformly spaced t (the integrals use one step)")
        phi, dphi = self.kernels((t[-1] - t[0]) / (len(t) - 1))
        h, m = len(phi) // 2, len(x)
        integral, by_parts = np.zeros_like(values), np.zeros_like(x)
        if m > 2 * h:
            integral[h:m - h] = oaconvolve(values, phi[::-1, None], mode="valid", axes=0)
            by_parts[h:m - h] = -oaconvolve(x, dphi[::-1, None], mode="valid", axes=0)
        return integral, by_parts

    def _compute(self, x, t):
        raise ParameterError("WeakForm has no pointwise derivative to return; use it as a "
                             "model's differentiation_method ('weak'), or another method to "
                             "differentiate")


#: shortest window (the rectangle rule needs a few dozen samples per test function)
MIN_WINDOW = 61
#: the window is this fraction of the GCV smoothing window (chosen on Van der Pol and
#: Duffing at 0-20 % noise against 0.5x, 1x, 2x; 1x and 2x lost the right terms at 20 %)
WINDOW_SCALE = 0.5
