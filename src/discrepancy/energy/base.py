"""What both energy models share: measured positions -> states -> ``E0 - H_m``."""
from __future__ import annotations

import numpy as np

from ..base import Estimator
from ..constraints import InstanceOf, Predicate, is_callable
from ..data.trajectory import as_2d, as_times
from ..differentiation import Differentiator, SavitzkyGolay, get_differentiation_method
from ..errors import ParameterError, PriorError, ShapeError, describe
from ..symbolic import IDENTIFIER
from .metrics import error_summary

NAMES = [None, Predicate(lambda v: isinstance(v, (list, tuple)) and len(v) > 0 and all(
    isinstance(n, str) and IDENTIFIER.match(n) for n in v), "a list of identifiers")]
DIFFERENTIATION = [None, InstanceOf(Differentiator, "a Differentiator"),
                   InstanceOf(str, "a spec string")]


def _finite_number(name: str, value) -> float:
    """``value`` as a float, or ParameterError naming ``name`` (a finite real number)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.number)) \
            or not np.isfinite(value):
        raise ParameterError(f"{name} must be a finite number (J); got {value!r:.80}")
    return float(value)


class EnergyModel(Estimator):
    """Base of the energy discrepancy models: ``dH(t) = E0 - H_m(x(t))`` from measured
    positions ``q`` ``(m, k)`` (and, optionally, velocities ``dq``).

    Args (shared):
        energy: ``H_m(x)`` for ``x = [q, dq]`` ``(m, 2k)`` -> ``(m,)`` (J), e.g.
            ``DoublePendulum().energy``.
        differentiation_method: turns positions into ``(q_smooth, dq)`` (default
            Savitzky-Golay, window 31, cubic).
        position_names: names of the ``k`` coordinates (default ``q1 ... qk``); the
            velocities are ``d`` + each name (``dq1 ...``). Take them from a system:
            ``position_names=system.state_names[:k]``.
    """

    _fit_hint = "fit(q, t)"
    _fitted_attribute = "coef_"

    def states(self, q, t, *, dq=None) -> tuple[np.ndarray, np.ndarray]:
        """``(x, t)``: ``x = [q_smooth, dq]`` ``(m', 2k)`` from positions ``q`` ``(m, k)``.

        When ``dq`` is not given it is estimated with ``differentiation_method`` and the
        samples within the method's half window of either end are dropped: there the
        derivative is a one-sided extrapolation, and its error in ``H_m`` would set ``E0``.
        """
        q = as_2d("q", q, allow_1d=True)
        k = q.shape[1]
        if self.position_names is not None and len(self.position_names) != k:
            raise ShapeError(f"q has {k} columns; position_names has {len(self.position_names)}"
                             f" names: {list(self.position_names)}")
        t = as_times("t", t, q.shape[0])
        if dq is not None:
            return np.hstack([q, as_2d("dq", dq, n_rows=q.shape[0], n_cols=k,
                                       allow_1d=True)]), t
        method = self.differentiation_method
        method = SavitzkyGolay(window_length=31, polyorder=3) if method is None \
            else get_differentiation_method(method)
        q_smooth, dq = method.smooth_and_differentiate(q, t)
        h = method.edge
        keep = slice(h, q.shape[0] - h)
        return np.hstack([q_smooth, dq])[keep], t[keep]

    def variable_names(self, k: int) -> list[str]:
        """``[q1 ... qk, dq1 ... dqk]`` (or the given position names and ``d`` + each)."""
        if isinstance(k, (bool, np.bool_)) or not isinstance(k, (int, np.integer)) or k < 1:
            raise ParameterError(f"k (the number of positions) must be an integer >= 1; got "
                                 f"{k!r}")
        positions = list(self.position_names) if self.position_names is not None else \
            [f"q{i + 1}" for i in range(k)]
        return [*positions, *[f"d{name}" for name in positions]]

    def _energy(self, x) -> np.ndarray:
        try:
            value = self.energy(x)
        except Exception as e:
            raise PriorError(f"energy(x) raised {type(e).__name__}: {e} (x of shape "
                             f"{x.shape})") from e
        if np.iscomplexobj(value):
            raise PriorError("energy(x) must return real values; it returned complex ones")
        try:
            h = np.asarray(value, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            raise PriorError(f"energy(x) must return ({x.shape[0]},) numbers; got "
                             f"{describe(value)}") from None
        if h.shape != (x.shape[0],):
            raise ShapeError(f"energy(x) must return ({x.shape[0]},); got {h.shape}")
        if not np.all(np.isfinite(h)):
            row = int(np.argmax(~np.isfinite(h)))
            raise ShapeError(f"energy(x) returned a non-finite value at row {row} "
                             f"(x = {x[row]})")
        return h

    def measured_delta_h(self, x, *, e0: float | None = None) -> np.ndarray:
        """``E0 - H_m(x)`` (J), ``(m,)``, with ``E0 = H_m(x[0])`` unless given."""
        x = as_2d("x", x)
        if x.shape[1] % 2:
            raise ShapeError(f"x must hold positions then velocities, (m, 2k); got shape "
                             f"{x.shape}")
        h = self._energy(x)
        return (h[0] if e0 is None else _finite_number("e0", e0)) - h

    def predict(self, q, t, *, dq=None, start: float = 0.0) -> np.ndarray:
        """Model ``dH`` (J) along a trajectory of positions ``q`` (velocities ``dq`` if
        measured), ``(m',)``; ``start``: its value at the first sample (see the subclass)."""
        self.check_is_fitted()
        x, t = self.states(q, t, dq=dq)
        return self._predict(x, t, _finite_number("start", start))

    def score(self, q, t, *, dq=None, start: float = 0.0) -> dict[str, float]:
        """Percentage errors (the paper's ``max|dH|`` and the window's ``dH`` range) of
        :meth:`predict` on a trajectory."""
        self.check_is_fitted()
        x, t = self.states(q, t, dq=dq)
        return error_summary(self.measured_delta_h(x),
                             self._predict(x, t, _finite_number("start", start)))

    def _predict(self, x, t, start: float) -> np.ndarray:
        """Hook: model ``dH`` for states ``x = [q, dq]``."""
        raise NotImplementedError


ENERGY = [is_callable]
