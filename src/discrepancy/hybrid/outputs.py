"""What is measured: the map ``y = h(x)`` from the model's states to the recorded outputs.

``outputs`` is a list with one entry per measured signal: a state (its name or index) or a
sympy expression in the state names (``sp.Min(h2, 10)`` for a sensor that saturates).
"""
from __future__ import annotations

import numpy as np
import sympy as sp

from ..errors import ParameterError, ShapeError, UnknownNameError
from ..symbolic import adopt, compile_numpy, symbol, to_casadi
from .casadi_form import casadi_module


class OutputMap:
    """``h(x)``: values ``(m, k)`` and Jacobians ``(m, k, n)`` along a trajectory.

    Attributes:
        selected: ``(k,)`` state indices when every output is a state, else ``None``.
        names: a readable name per output.
    """

    def __init__(self, outputs, state_names):
        if outputs is None:
            raise ParameterError("outputs is required: the states (names or indices) or "
                                 "sympy expressions of them that y measures, one per column")
        items = [outputs] if isinstance(outputs, (str, int, sp.Basic)) else list(outputs)
        if not items:
            raise ParameterError("outputs must name at least one measured quantity")
        names = list(state_names)
        self.state_names, self.n = names, len(names)
        self.expressions, self.names, selected = [], [], []
        for i, item in enumerate(items):
            if isinstance(item, (int, np.integer)) and not isinstance(item, bool):
                if not 0 <= item < self.n:
                    raise ShapeError(f"outputs[{i}] = {item} is not a state index (0..."
                                     f"{self.n - 1})")
                item = names[int(item)]
            if isinstance(item, str):
                if item not in names:
                    raise UnknownNameError(f"outputs[{i}] = {item!r} is not a state; states: "
                                           f"{names}")
                selected.append(names.index(item))
                item = sp.Symbol(item)
            expr = adopt(item, names, label=f"outputs[{i}]")
            self.expressions.append(expr)
            self.names.append(str(item))
        self.k = len(self.expressions)
        self.selected = np.array(selected) if len(selected) == self.k else None
        self._values = [compile_numpy(e, names) for e in self.expressions]
        self._jacobian = None      # dh/dx by CasADi, built on first use (needs [control])

    def _casadi_jacobian(self):
        """``dh/dx`` by CasADi (exact through saturations such as ``Min``)."""
        ca = casadi_module()
        x = ca.SX.sym("x", self.n)
        symbols = {name: x[i] for i, name in enumerate(self.state_names)}
        h = ca.vertcat(*[ca.SX(to_casadi(e, symbols, term=f"outputs[{i}]"))
                         for i, e in enumerate(self.expressions)])
        return ca.Function("dh", [x], [ca.jacobian(h, x)])

    def __call__(self, states: np.ndarray) -> np.ndarray:
        if self.selected is not None:
            return states[:, self.selected]
        return np.column_stack([f(states) for f in self._values])

    def jacobian(self, states: np.ndarray) -> np.ndarray:
        """Derivatives of the ``k`` outputs by the ``n`` states at ``states`` ``(m, n)``:
        ``(m, k, n)``."""
        m = states.shape[0]
        if self.selected is not None:
            out = np.zeros((m, self.k, self.n))
            out[:, np.arange(self.k), self.selected] = 1.0
            return out
        if self._jacobian is None:
            self._jacobian = self._casadi_jacobian()
        flat = np.asarray(self._jacobian.map(m)(states.T))    # (k, m n): sample j's block
        return flat.reshape(self.k, m, self.n).transpose(1, 0, 2)

    def initial_guess(self, y0: np.ndarray) -> np.ndarray:
        """``x0`` guess: measured states from the first outputs, the others zero."""
        x0 = np.zeros(self.n)
        if self.selected is not None:
            x0[self.selected] = y0
        return x0

    @property
    def measured(self) -> set[int]:
        """Indices of the states that appear in an output."""
        used = set().union(*(e.free_symbols for e in self.expressions))
        return {i for i, name in enumerate(self.state_names) if symbol(name) in used}
