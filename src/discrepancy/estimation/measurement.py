"""What a filter measures: ``y = h(x)``, parsed as ``fit_outputs`` parses ``outputs``
(state names or indices, or sympy expressions of the states), evaluated in numpy or
written in CasADi."""
from __future__ import annotations

import numpy as np

from ..models.outputs import OutputMap
from ..symbolic import to_casadi
from .backends import FD_STEP


class Measurement:
    """``h(x)`` of ``outputs`` for states named ``state_names``.

    Attributes:
        k: number of outputs.
        n: number of states.
        names: a readable name per output.
        selected: the state index of each output when every output is a state, else
            ``None``.
    """

    def __init__(self, outputs, state_names):
        self._map = OutputMap(outputs, state_names)
        self.k, self.n = self._map.k, self._map.n
        self.names, self.selected = list(self._map.names), self._map.selected
        if self.selected is not None:
            self._H = np.zeros((self.k, self.n))
            self._H[np.arange(self.k), self.selected] = 1.0

    def values(self, states: np.ndarray) -> np.ndarray:
        """``h`` of states ``(m, n)``: ``(m, k)``."""
        return self._map(states)

    def jacobian_at(self, x: np.ndarray) -> np.ndarray:
        """``∂h/∂x`` ``(k, n)`` at one state: exact for measured states, else by central
        differences (the numpy backend; CasADi differentiates ``h`` symbolically)."""
        if self.selected is not None:
            return self._H
        step = FD_STEP * np.maximum(1.0, np.abs(x))
        values = self._map(np.vstack([x + np.diag(step), x - np.diag(step)]))
        return ((values[:self.n] - values[self.n:]) / (2 * step[:, None])).T

    def casadi(self, x):
        """CasADi column ``(k, 1)`` of ``h`` at the symbol ``x`` ``(n, 1)``."""
        import casadi as ca

        if self.selected is not None:
            return ca.vertcat(*[x[int(i)] for i in self.selected])
        symbols = {name: x[i] for i, name in enumerate(self._map.state_names)}
        return ca.vertcat(*[ca.SX(to_casadi(e, symbols, term=f"outputs[{i}]"))
                            for i, e in enumerate(self._map.expressions)])

    @property
    def measured(self) -> set[int]:
        """Indices of the states that appear in an output (directly or inside an expression)."""
        return self._map.measured
