"""Libraries of spatial derivatives for PDEs: products of fields and their derivatives.

A PDE fit sees, at every grid point and time, the variables ``z = [fields, derivatives,
inputs]``: the fields (``u``, ``v``), their spatial derivatives up to some order named
after the grid's coordinates (``u_x``, ``u_xx``, ``u_xy``; see :func:`derivative_name`)
and the inputs. Any library acts on them like on states: ``CustomLibrary([u * u_xxx])``
is exact, ``PolynomialLibrary(2, variables=["u", "v"])`` gives reaction terms, and
:class:`PDELibrary` builds PySINDy's PDE-FIND library (same columns, same order):

    [1], f(fields)..., pure derivatives (per derivative, per field), and
    f(fields) * derivative for every pair (per derivative, per field, per f).

Libraries compose with ``+`` and ``*`` as everywhere else (duplicate columns dropped).
"""
from __future__ import annotations

import re
from itertools import product

import numpy as np
import sympy as sp

from ..constraints import InstanceOf, Integral, Interval, Predicate
from ..errors import UnknownNameError
from ..symbolic import symbol
from .base import ConcatLibrary, FeatureLibrary, TensorLibrary, check_names
from .custom import CustomLibrary
from .polynomial import PolynomialLibrary

#: a derivative variable: field name, "_", one coordinate letter per differentiation
DERIVATIVE = re.compile(r"^(?P<field>[A-Za-z_][A-Za-z0-9_]*)_(?P<axes>[a-z]+)$")


def multiindices(ndim: int, order: int) -> list[tuple[int, ...]]:
    """Derivative multi-indices ``α`` with ``1 <= |α| <= order`` in PySINDy's order
    (``itertools.product`` over the axes): ``(0, 1), (0, 2), (1, 0), (1, 1), (2, 0)``."""
    return [a for a in product(range(order + 1), repeat=ndim) if 0 < sum(a) <= order]


def derivative_name(field: str, alpha, coordinates) -> str:
    """``u_xxy`` for ``∂x² ∂y u``: the field, ``_``, each coordinate repeated ``α`` times."""
    return f"{field}_" + "".join(c * k for c, k in zip(coordinates, alpha, strict=True))


def parse_derivative(name: str, fields, coordinates) -> tuple[str, tuple[int, ...]] | None:
    """``(field, α)`` for a derivative variable of one of ``fields`` (else ``None``)."""
    match = DERIVATIVE.match(name)
    if not match or match["field"] not in fields:
        return None
    letters = match["axes"]
    if not set(letters) <= set(coordinates) or \
            letters != "".join(sorted(letters, key=list(coordinates).index)):
        return None
    return match["field"], tuple(letters.count(c) for c in coordinates)


def derivative_order_of(names, fields, coordinates) -> int:
    """Highest derivative order among variable ``names`` (0 if none is a derivative)."""
    found = [parse_derivative(n, fields, coordinates) for n in names]
    return max((sum(a) for f in found if f for a in [f[1]]), default=0)


def library_derivative_order(library, fields, coordinates) -> int:
    """Highest spatial derivative order a library (tree) needs: a :class:`PDELibrary`'s
    ``derivative_order``, and the derivative symbols of custom expressions."""
    if isinstance(library, PDELibrary):
        return int(library.derivative_order)
    if isinstance(library, ConcatLibrary):
        return max(library_derivative_order(p, fields, coordinates) for p in library._parts())
    if isinstance(library, TensorLibrary):
        return max(library_derivative_order(p, fields, coordinates)
                   for p in (library.left, library.right))
    if isinstance(library, CustomLibrary) and library.expressions is not None:
        names = {s.name for e in library.expressions if isinstance(e, sp.Basic)
                 for s in e.free_symbols}
        return derivative_order_of(names, fields, coordinates)
    return 0


class PDELibrary(FeatureLibrary):
    """PDE-FIND's library over the fields and their spatial derivatives.

    Args:
        function_library: terms in the fields alone (default ``PolynomialLibrary(2,
            include_bias=False)``), fitted on the field names.
        derivative_order: highest total order of the spatial derivatives (>= 1).
        include_bias: a constant column first.
        include_interaction: the products ``f(fields) * derivative`` (PySINDy's option).
        fields: names of the fields the library uses (default: every variable that has
            derivative variables ``name_x``... among the names it is fitted to).

    Fitted to variable names holding the fields' derivative variables (the PDE model
    supplies them); ``fit(["u", "u_x", "u_xx"])`` by hand works as well.
    """

    _parameter_constraints = {
        "function_library": [None, InstanceOf(FeatureLibrary, "a feature library")],
        "derivative_order": [Interval(Integral, 1, 8)], "include_bias": [bool],
        "include_interaction": [bool],
        "fields": [None, Predicate(lambda v: isinstance(v, (list, tuple)) and v and all(
            isinstance(e, str) for e in v), "a non-empty list of field names")]}

    def __init__(self, function_library: FeatureLibrary | None = None,
                 derivative_order: int = 2, *, include_bias: bool = False,
                 include_interaction: bool = True, fields=None):
        self.function_library = function_library
        self.derivative_order = derivative_order
        self.include_bias = include_bias
        self.include_interaction = include_interaction
        self.fields = fields

    def fit(self, names):
        self._validate_params()
        names = check_names(names)
        fields, coordinates = self._fields(names)
        index = {n: i for i, n in enumerate(names)}
        derivs, missing = [], []
        for alpha in multiindices(len(coordinates), self.derivative_order):
            for f in fields:
                name = derivative_name(f, alpha, coordinates)
                (derivs if name in index else missing).append(name)
        if missing:
            raise UnknownNameError(f"PDELibrary(derivative_order={self.derivative_order}) "
                                   f"needs the derivative variables {missing[:6]}, which are "
                                   f"not among the variables {names}")
        import copy

        functions = copy.deepcopy(self.function_library or PolynomialLibrary(
            2, include_bias=False)).fit(fields)
        self._function_library, self._field_index = functions, [index[f] for f in fields]
        self._deriv_index = [index[d] for d in derivs]
        f_exprs = list(functions.feature_expressions_)
        d_exprs = [symbol(d) for d in derivs]
        exprs = ([sp.S.One] if self.include_bias else []) + f_exprs + d_exprs
        if self.include_interaction:
            exprs += [f * d for d in d_exprs for f in f_exprs]
        seen, self._keep = set(), []
        for i, e in enumerate(exprs):
            if e not in seen:
                seen.add(e)
                self._keep.append(i)
        self._bind(names, [exprs[i] for i in self._keep])
        return self

    def _fields(self, names) -> tuple[list[str], list[str]]:
        """The fields and coordinate letters found among ``names``."""
        parsed = [DERIVATIVE.match(n) for n in names]
        coordinates = []
        for m in parsed:
            if m and m["field"] in names and len(m["axes"]) == 1 and \
                    m["axes"] not in coordinates:
                coordinates.append(m["axes"])
        found = [n for n in names if any(f"{n}_{c}" in names for c in coordinates)]
        # the grid's axis order, read from mixed derivatives (u_xy: x before y)
        mixed = {(a, b) for f in found for a in coordinates for b in coordinates
                 if a != b and f"{f}_{a}{b}" in names}
        coordinates.sort(key=lambda c: (sum((b, c) in mixed for b in coordinates), c))
        fields = found if self.fields is None else list(self.fields)
        unknown = sorted(set(fields) - set(found))
        if unknown or not fields:
            raise UnknownNameError(f"PDELibrary: fields {unknown or fields} have no derivative "
                                   f"variables (such as {(unknown or ['u'])[0]}_x) among the "
                                   f"variables {names}; fit it inside PDEDiscrepancyModel or "
                                   "give the derivative variables")
        return fields, coordinates

    def user_functions(self):
        return self._function_library.user_functions() if hasattr(
            self, "_function_library") else {}

    def _transform(self, Z):
        functions = self._function_library._transform(Z[:, self._field_index])
        derivs = Z[:, self._deriv_index]
        parts = ([np.ones((Z.shape[0], 1))] if self.include_bias else []) + [functions, derivs]
        if self.include_interaction:
            parts.append((derivs[:, :, None] * functions[:, None, :]).reshape(Z.shape[0], -1))
        theta = np.hstack(parts)
        return theta if len(self._keep) == theta.shape[1] else theta[:, self._keep]

