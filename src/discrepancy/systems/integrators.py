"""Fixed-step integration used to generate reference data exactly as the paper did (RK4)."""
from __future__ import annotations

from collections.abc import Callable

import numpy as np


def rk4(rhs: Callable[[np.ndarray], np.ndarray], x0, t: np.ndarray) -> np.ndarray:
    """Classical 4th-order Runge–Kutta on the grid ``t`` ``(k,)``; ``rhs``: ``(m, n) -> (m, n)``.

    Returns ``(k, n)``. Written out because scipy has no fixed-step RK4 and the paper's
    data are defined by this scheme.
    """
    x = np.empty((len(t), np.size(x0)))
    x[0] = np.asarray(x0, dtype=float)
    for i, h in enumerate(np.diff(t)):
        xi = x[i][None, :]
        k1 = rhs(xi)
        k2 = rhs(xi + h / 2 * k1)
        k3 = rhs(xi + h / 2 * k2)
        k4 = rhs(xi + h * k3)
        x[i + 1] = (xi + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4))[0]
    return x
