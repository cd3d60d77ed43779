"""Fixed-step integration used to generate reference data exactly as the paper did (RK4)."""
from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..runge_kutta import runge_kutta_step


def rk4(rhs: Callable[[np.ndarray], np.ndarray], x0, t: np.ndarray) -> np.ndarray:
    """Classical 4th-order Runge–Kutta on the grid ``t`` ``(k,)``; ``rhs``: ``(m, n) -> (m, n)``.

    Returns ``(k, n)``: the paper's data are defined by this scheme (the step is
    :func:`discrepancy.runge_kutta.runge_kutta_step`).
    """
    x = np.empty((len(t), np.size(x0)))
    x[0] = np.asarray(x0, dtype=float)
    for i, h in enumerate(np.diff(t)):
        x[i + 1] = runge_kutta_step(lambda z, _: rhs(z), x[i][None, :], h)[0]
    return x
