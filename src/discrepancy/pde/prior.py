"""The PDE prior ``N_m``: sympy expressions in the jet variables, or the user's solver.

* A list of sympy expressions, one per field, in the fields, their derivatives named as
  :func:`~discrepancy.libraries.pde.derivative_name` (``u_xx``) and the inputs:
  ``[-u * u_x + 0.05 * u_xx]``. Exact: exported, integrated by parts in the weak form,
  split into stiff linear and nonlinear parts for simulation.
* A callable ``N_m(u)`` or ``N_m(u, inputs)`` taking snapshots ``(k, *grid.shape, n)``
  (inputs ``(k, *grid.shape, r)``) and returning ``u_t`` of the same shape: the right-hand
  side of the user's own solver, with its own spatial discretisation.
* ``None``: plain PDE-FIND.
"""
from __future__ import annotations

import inspect

import numpy as np
import sympy as sp

from ..errors import ExportError, ParameterError, PriorError, describe
from ..libraries.pde import derivative_order_of
from ..symbolic import adopt, compile_numpy


class FieldPrior:
    """A checked prior for fields (see the module docstring).

    Args:
        prior: expressions, callable or ``None``.
        fields, coordinates, inputs: names of the variables it may use.
    """

    def __init__(self, prior, fields, coordinates, inputs=()):
        self.fields, self.coordinates = list(fields), list(coordinates)
        self.inputs = list(inputs)
        self.expressions: list[sp.Expr] | None = None
        self._call = None
        self._compiled_for: dict = {}
        if prior is None:
            return
        if callable(prior) and not isinstance(prior, sp.Basic):
            self._call = _adapt(prior)
        elif isinstance(prior, (list, tuple)):
            if len(prior) != len(self.fields):
                raise ParameterError(f"prior must have one expression per field "
                                     f"({len(self.fields)}: {self.fields}); got {len(prior)}")
            names = self._allowed_names(prior)
            self.expressions = [adopt(e, names, label=f"prior[{i}]")
                                for i, e in enumerate(prior)]
        else:
            raise ParameterError("prior must be None, a callable N_m(u) on snapshots or a "
                                 f"list of sympy expressions; got {describe(prior)}")

    def _allowed_names(self, prior) -> list[str]:
        """Fields, inputs and any derivative of the fields the expressions name."""
        used = {s.name for e in prior if isinstance(e, sp.Basic) for s in e.free_symbols}
        order = derivative_order_of(used, self.fields, self.coordinates)
        from .variables import FieldVariables
        return FieldVariables(tuple(self.fields), tuple(self.coordinates), tuple(self.inputs),
                              order).names

    @property
    def is_symbolic(self) -> bool:
        """True when the prior is sympy expressions (exact: exported, integrated by parts in
        the weak form); False for a callable or no prior."""
        return self.expressions is not None

    @property
    def order(self) -> int:
        """Highest spatial derivative the expressions use (0 for a callable or none)."""
        if not self.expressions:
            return 0
        used = {s.name for e in self.expressions for s in e.free_symbols}
        return derivative_order_of(used, self.fields, self.coordinates)

    def values(self, u: np.ndarray, inputs, jet: np.ndarray | None, names) -> np.ndarray:
        """``N_m`` on snapshots ``u`` ``(k, *shape, n)``: ``jet`` (the variables ``names``
        on the same points) serves the expressions; the callable sees ``u`` itself."""
        if self._call is None and self.expressions is None:
            return np.zeros_like(u)
        if self.expressions is not None:
            flat = jet.reshape(-1, jet.shape[-1])
            key = tuple(names)
            if key not in self._compiled_for:
                self._compiled_for[key] = [self._compiled(i, e, names)
                                           for i, e in enumerate(self.expressions)]
            out = np.stack([f(flat) for f in self._compiled_for[key]], axis=-1)
            return out.reshape(u.shape)
        return self._called(u, inputs)

    def _compiled(self, i, expr, names):
        try:
            f = compile_numpy(expr, names)
        except ExportError as e:
            raise PriorError(f"prior[{i}] = {expr} cannot be evaluated: {e}") from None
        return lambda z: np.broadcast_to(f(z), (z.shape[0],))

    def _called(self, u, inputs):
        try:
            out = self._call(u, inputs)
        except Exception as e:
            raise PriorError(f"prior raised {type(e).__name__}: {e} when called with "
                             f"snapshots of shape {u.shape}") from e
        if np.iscomplexobj(out):
            raise PriorError("prior must return real values; it returned complex ones")
        try:
            out = np.asarray(out, dtype=float)
        except (TypeError, ValueError):
            raise PriorError(f"prior must return an array of shape {u.shape}; it returned "
                             f"{describe(out)}") from None
        if out.shape != u.shape:
            raise PriorError(f"prior must return an array of shape {u.shape} (that of the "
                             f"snapshots it was given); got shape {out.shape}")
        if not np.all(np.isfinite(out)):
            index = tuple(int(i) for i in np.argwhere(~np.isfinite(out))[0])
            raise PriorError(f"prior returned non-finite values (first at snapshot "
                             f"{index[0]}, grid point {index[1:-1]}, field {index[-1]})")
        return out


def _adapt(f):
    """Call ``f(u, inputs)``, or ``f(u)`` when it takes one argument."""
    try:
        params = [p for p in inspect.signature(f).parameters.values()
                  if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD, p.VAR_POSITIONAL)]
    except (TypeError, ValueError):
        return f
    if len(params) == 1 and params[0].kind != params[0].VAR_POSITIONAL:
        return lambda u, inputs: f(u)
    return f
