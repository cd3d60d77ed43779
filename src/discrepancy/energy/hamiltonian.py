"""The paper's form: ``dH = E0 - H_m(x)`` regressed on a library of state functions.

``dH(t)`` is the energy dissipated up to ``t``, a path integral, not a function of the
current state. A library that spans ``H_m``'s own terms fits it exactly as ``E0 - H_m``
(a tautology: zero training error, no friction learned, wrong by ``E0' - E0`` on any
trajectory that starts with another energy ``E0'``); one that does not span them cannot
represent ``dH``. :func:`energy_span_residual` tells the two cases apart.
"""
from __future__ import annotations

import warnings

import numpy as np

from ..data.validation import check_array
from ..errors import ParameterError

# Below this relative residual the library reproduces H_m to within ~0.1 % of its variation.
SPAN_TOLERANCE = 1e-3


class EnergyTautologyWarning(UserWarning):
    """The state library spans the model energy, so ``dH = E0 - H_m`` is fitted trivially."""


def energy_span_residual(theta: np.ndarray, energy: np.ndarray) -> float:
    """Relative residual ``|H_m - Theta c| / |H_m - mean(H_m)|`` of the best ``c`` (least squares).

    About 0 when the library spans ``H_m`` along the data; 1 when it explains none of it.
    """
    theta = check_array("theta", theta, allow_1d=True)
    energy = check_array("energy", energy, ndim=1, n_rows=theta.shape[0])
    design = np.column_stack([np.ones(len(energy)), theta])
    coef, *_ = np.linalg.lstsq(design, energy, rcond=None)
    spread = np.linalg.norm(energy - energy.mean())
    return float(np.linalg.norm(energy - design @ coef) / max(spread, 1e-300))


def check_span(theta: np.ndarray, energy: np.ndarray, *, tolerance: float = SPAN_TOLERANCE
               ) -> float:
    """Warn (:class:`EnergyTautologyWarning`) if the library spans ``H_m``; return the residual."""
    if isinstance(tolerance, bool) or not isinstance(tolerance, (int, float, np.number)) \
            or not 0 < tolerance < 1:
        raise ParameterError(f"tolerance must be a number in (0, 1); got {tolerance!r}")
    residual = energy_span_residual(theta, energy)
    if residual < tolerance:
        warnings.warn(
            f"the feature library spans the model energy H_m along the data (relative residual "
            f"{residual:.2e} < {tolerance:g}), so dH = E0 - H_m is fitted exactly by "
            "E0 - H_m itself: near-zero training error means nothing, no friction is learned, "
            "and the model is off by the difference of initial energies on any other trajectory. "
            "Use DissipationDiscrepancy (friction laws) or a library without H_m's terms.",
            EnergyTautologyWarning, stacklevel=3)
    return residual
