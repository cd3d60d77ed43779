"""Spatial derivatives of fields on uniform grids: spectral, finite differences, Savitzky-Golay.

Every method differentiates an array along one axis with a given grid step, periodic or
not, to any order (:meth:`SpatialDifferentiator.derivative`); mixed derivatives (``u_xy``)
are derivatives along one axis after the other.

* :class:`SpatialSpectral`: the discrete Fourier transform (numpy), exact for band-limited
  periodic fields; ``cutoff`` low-passes noisy ones. Periodic axes only.
* :class:`SpatialFiniteDifference`: centred stencils of the given accuracy in the interior
  and one-sided ones of ``d + order`` points at non-periodic ends, the stencils of PySINDy's
  ``FiniteDifference`` (so PDE-FIND fits agree with it to rounding).
* :class:`SpatialSavitzkyGolay`: the derivative of a local least-squares polynomial (noise
  smoothing); at non-periodic ends the polynomial of the first/last window.

Local stencils are applied by hand (a few shifted slices, or edge matrices) because numpy's
``gradient`` offers only first derivatives of second order, and scipy's filters no one-sided
ends of matching accuracy.
"""
from __future__ import annotations

from abc import ABC, abstractmethod
from math import factorial

import numpy as np

from ..base import Estimator
from ..constraints import Integral, Interval, Real
from ..errors import ParameterError, ShapeError
from ..registry import Registry
from .methods import MAX_POLYORDER, ODD_WINDOW
from .savgol import savgol_coefficients


class SpatialDifferentiator(Estimator, ABC):
    """Derivatives of fields along one spatial axis (see the module docstring)."""

    #: whether the method works only on periodic axes
    periodic_only: bool = False

    def derivative(self, u: np.ndarray, axis: int, order: int, spacing: float,
                   periodic: bool, *, check: bool = True) -> np.ndarray:
        """The ``order``-th derivative of ``u`` along ``axis`` (grid step ``spacing``);
        same shape as ``u``. ``check=False`` skips the checks (a hot loop that made them
        once, such as a simulation's right-hand side)."""
        if not check:
            return u if order == 0 else self._derivative(u, axis, order, float(spacing),
                                                         bool(periodic))
        self._validate_params()
        if self.periodic_only and not periodic:
            raise ParameterError(f"{type(self).__name__} needs a periodic axis; this axis is "
                                 "not periodic: use SpatialFiniteDifference() or "
                                 "SpatialSavitzkyGolay(), or declare the grid periodic")
        if u.shape[axis] < self.min_points(order):
            raise ShapeError(f"{self!r} needs at least {self.min_points(order)} grid points "
                             f"for a derivative of order {order}; the axis has {u.shape[axis]}")
        if order == 0:
            return u
        return self._derivative(u, axis, order, float(spacing), bool(periodic))

    def min_points(self, order: int) -> int:
        """Fewest points along an axis for a derivative of ``order``."""
        return order + 1

    @abstractmethod
    def _derivative(self, u, axis, order, spacing, periodic) -> np.ndarray:
        """Hook: the derivative (arguments validated)."""


SPATIAL_METHODS = Registry("spatial differentiation method", "spatial_differentiation",
                           SpatialDifferentiator)


@SPATIAL_METHODS.register("spectral")
class SpatialSpectral(SpatialDifferentiator):
    """Fourier derivative on periodic axes (``rfft``): ``(i k)^d`` times each mode.

    Args:
        cutoff: keep wavenumbers up to this fraction of the Nyquist wavenumber (1: all).

    The Nyquist mode of an even number of points is dropped from odd derivatives (it has
    no real derivative), as PySINDy's ``SpectralDerivative`` does in effect.
    """

    periodic_only = True
    _parameter_constraints = {"cutoff": [Interval(Real, 0, 1, closed="right")]}

    def __init__(self, cutoff: float = 1.0):
        self.cutoff = cutoff

    def _derivative(self, u, axis, order, spacing, periodic):
        n = u.shape[axis]
        k = 2 * np.pi * np.fft.rfftfreq(n, d=spacing)
        factor = (1j * k) ** order
        factor[k > self.cutoff * k[-1] * (1 + 1e-12)] = 0.0
        if n % 2 == 0 and order % 2 == 1:
            factor[-1] = 0.0
        shape = [1] * u.ndim
        shape[axis] = len(k)
        return np.fft.irfft(np.fft.rfft(u, axis=axis) * factor.reshape(shape), n=n, axis=axis)

    def smooth(self, u, axis):
        """The field low-passed at ``cutoff`` along ``axis``."""
        if self.cutoff >= 1:
            return u
        n = u.shape[axis]
        keep = np.arange(n // 2 + 1) <= self.cutoff * (n // 2) * (1 + 1e-12)
        shape = [1] * u.ndim
        shape[axis] = len(keep)
        return np.fft.irfft(np.fft.rfft(u, axis=axis) * keep.reshape(shape), n=n, axis=axis)


class _Stencil(SpatialDifferentiator):
    """A local linear stencil: interior weights and edge matrices (non-periodic ends)."""

    @abstractmethod
    def stencil(self, order: int, spacing: float):
        """``(weights, left_reach, left_edge, right_edge)``: the interior weights at offsets
        ``-left_reach ...``; ``left_edge`` ``(a, k)`` gives the first ``a`` points from the
        first ``k``, ``right_edge`` ``(b, k)`` the last ``b`` from the last ``k``."""

    def _derivative(self, u, axis, order, spacing, periodic):
        weights, a, left, right = self.stencil(order, spacing)
        return apply_stencil(u, axis, weights, a, left, right, periodic)


def apply_stencil(u, axis, weights, a, left, right, periodic):
    """Apply a stencil along ``axis`` (see ``_Stencil.stencil``); periodic axes wrap."""
    u = np.moveaxis(u, axis, 0)
    n, b = u.shape[0], len(weights) - 1 - a
    if periodic:
        padded = np.concatenate([u[n - a:], u, u[:b]]) if a or b else u
        out = _correlate(padded, weights, n)
    else:
        out = np.empty_like(u)
        out[a:n - b] = _correlate(u, weights, n - a - b)
        out[:left.shape[0]] = np.tensordot(left, u[:left.shape[1]], axes=(1, 0))
        out[n - right.shape[0]:] = np.tensordot(right, u[n - right.shape[1]:], axes=(1, 0))
    return np.moveaxis(out, 0, axis)


def _correlate(u, weights, count):
    out = np.zeros((count, *u.shape[1:]))
    for j, w in enumerate(weights):
        if w != 0:
            out += w * u[j:j + count]
    return out


def _taylor_weights(offsets, order: int, spacing: float) -> np.ndarray:
    """Weights of the ``order``-th derivative at 0 from samples at ``offsets`` (steps):
    exact for polynomials of degree ``len(offsets) - 1``."""
    powers = np.arange(len(offsets))[:, None]
    matrix = (np.asarray(offsets, float) * spacing)[None, :] ** powers
    rhs = np.zeros(len(offsets))
    rhs[order] = factorial(order)
    return np.linalg.solve(matrix, rhs)


@SPATIAL_METHODS.register("finite_difference")
class SpatialFiniteDifference(_Stencil):
    """Finite differences of accuracy ``order`` (PySINDy's stencils, see the module
    docstring). No smoothing: for clean fields."""

    _parameter_constraints = {"order": [Interval(Integral, 1, 10)]}

    def __init__(self, order: int = 2):
        self.order = order

    def _sizes(self, d: int) -> tuple[int, int]:
        return 2 * ((d + 1) // 2) - 1 + self.order, d + self.order

    def min_points(self, order):
        return max(self._sizes(order))

    def stencil(self, d, spacing):
        central, one_sided = self._sizes(d)
        a = (central - 1) // 2
        b = central - 1 - a
        weights = _taylor_weights(np.arange(central) - a, d, spacing)
        left = np.array([_taylor_weights(np.arange(one_sided) - i, d, spacing)
                         for i in range(a)]).reshape(a, one_sided)
        right = np.array([_taylor_weights(np.arange(one_sided) - (one_sided - b + i), d,
                                          spacing) for i in range(b)]).reshape(b, one_sided)
        return weights, a, left, right


@SPATIAL_METHODS.register("savitzky_golay")
class SpatialSavitzkyGolay(_Stencil):
    """Derivative of the local least-squares polynomial of degree ``polyorder`` over
    ``window_length`` points (smooths noise; needs ``polyorder`` >= the derivative order)."""

    _parameter_constraints = {"window_length": [ODD_WINDOW],
                              "polyorder": [Interval(Integral, 1, MAX_POLYORDER)]}

    def __init__(self, window_length: int = 9, polyorder: int = 5):
        self.window_length = window_length
        self.polyorder = polyorder

    def _check_params(self):
        if self.polyorder >= self.window_length:
            raise ParameterError(f"SpatialSavitzkyGolay: polyorder ({self.polyorder}) must be "
                                 f"below window_length ({self.window_length})")

    def min_points(self, order):
        return self.window_length

    def stencil(self, d, spacing):
        if d > self.polyorder:
            raise ParameterError(f"SpatialSavitzkyGolay: a derivative of order {d} needs "
                                 f"polyorder >= {d}; got {self.polyorder}")
        w, h = self.window_length, self.window_length // 2
        weights = savgol_coefficients(w, self.polyorder, deriv=d, delta=spacing)
        edges = edge_matrix(w, self.polyorder, d, spacing)
        return weights, h, edges[:h], edges[w - h:]


def edge_matrix(window: int, polyorder: int, d: int, spacing: float) -> np.ndarray:
    """``(window, window)``: row ``i`` gives the ``d``-th derivative at point ``i`` of the
    least-squares polynomial through ``window`` samples."""
    h = window // 2
    s = (np.arange(window) - h) / h
    design = np.vander(s, polyorder + 1, increasing=True)
    derived = np.zeros_like(design)
    for p in range(d, polyorder + 1):
        derived[:, p] = factorial(p) / factorial(p - d) * s ** (p - d)
    return derived @ np.linalg.pinv(design) / (h * spacing) ** d


def get_spatial_method(method) -> SpatialDifferentiator:
    """A spatial method from an instance, a registered name or spec text."""
    return SPATIAL_METHODS.create(method)
