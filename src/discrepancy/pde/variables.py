"""The variables a PDE fit sees at every grid point: fields, spatial derivatives, inputs.

``FieldVariables(fields=("u",), coordinates=("x",), order=2).names`` is
``["u", "u_x", "u_xx"]``; :meth:`FieldVariables.jet` computes their values on snapshots
with one spatial method per axis (mixed derivatives one axis after the other).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..libraries.pde import derivative_name, multiindices


@dataclass(frozen=True)
class FieldVariables:
    """Names and orders of the variables ``z`` of a PDE fit.

    Attributes:
        fields: field names; coordinates: the grid's coordinate letters;
        inputs: input names; order: highest spatial derivative order computed.
    """

    fields: tuple[str, ...]
    coordinates: tuple[str, ...]
    inputs: tuple[str, ...] = ()
    order: int = 0

    @property
    def derivatives(self) -> list[tuple[tuple[int, ...], int, str]]:
        """``(α, field index, name)`` of every derivative variable, PySINDy's order."""
        return [(alpha, j, derivative_name(f, alpha, self.coordinates))
                for alpha in multiindices(len(self.coordinates), self.order)
                for j, f in enumerate(self.fields)]

    @property
    def names(self) -> list[str]:
        """Variable names in column order: the fields, then their derivatives (``u_x``,
        ``u_xx``, ...; see :attr:`derivatives`), then the inputs."""
        return [*self.fields, *(d[2] for d in self.derivatives), *self.inputs]

    @property
    def n_variables(self) -> int:
        """Number of variables, the last axis of :meth:`jet`."""
        return len(self.names)

    def with_order(self, order: int) -> FieldVariables:
        """The same fields, coordinates and inputs with derivatives up to ``order``."""
        return FieldVariables(self.fields, self.coordinates, self.inputs, order)

    def jet(self, u: np.ndarray, inputs: np.ndarray | None, grid, methods, *,
            check: bool = True) -> np.ndarray:
        """``(k, *grid.shape, n_variables)``: the variables on snapshots ``u``
        ``(k, *grid.shape, n_fields)`` (inputs ``(k, *grid.shape, r)`` or ``None``);
        ``methods``: one spatial differentiator per axis (``check=False``: already
        checked)."""
        parts = [u]
        cache = {(0,) * grid.ndim: u}
        for alpha in multiindices(grid.ndim, self.order):
            parts.append(_derivative(alpha, cache, grid, methods, check))
        if self.inputs:
            parts.append(inputs)
        return np.concatenate(parts, axis=-1)


def _derivative(alpha, cache, grid, methods, check):
    """``∂^α u`` of all fields, built from the cached derivative with one order less along
    the last axis that has one (so ``u_xy`` reuses ``u_x``)."""
    if alpha in cache:
        return cache[alpha]
    axis = max(i for i, a in enumerate(alpha) if a > 0)
    base = tuple(a if i != axis else 0 for i, a in enumerate(alpha))
    lower = _derivative(base, cache, grid, methods, check)
    value = methods[axis].derivative(lower, axis + 1, alpha[axis], grid.spacing[axis],
                                     grid.periodic[axis], check=check)
    cache[alpha] = value
    return value
