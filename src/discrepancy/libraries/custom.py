"""Custom library: user sympy expressions (exact) or named numpy functions."""
from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import numpy as np
import sympy as sp

from ..errors import ParameterError
from ..symbolic import IDENTIFIER, adopt, compile_numpy
from .base import BaseLibrary


class CustomLibrary(BaseLibrary):
    """Columns given by the user.

    Either ``expressions``: sympy expressions in the variables (build symbols with
    :func:`discrepancy.symbolic.symbol`, or any sympy Symbol with the variable's
    name); these are exact and export to sympy, LaTeX and CasADi. Or ``functions``:
    a mapping ``name -> numpy function of one array`` applied to each chosen
    variable (columns ``name(x1)``, ...); such terms cannot be exported to CasADi
    and must be passed again to :func:`discrepancy.load_model`.

    Args:
        expressions: sequence of sympy expressions.
        functions: mapping of identifier names to vectorised numpy callables.
        variables: variables the functions act on (names or indices); ``None`` = all.
    """

    def __init__(self, expressions: Sequence[sp.Expr] | None = None, *,
                 functions: Mapping[str, Callable] | None = None, variables=None):
        super().__init__(variables=variables)
        self.expressions = expressions
        self.functions = functions

    def _expressions(self, symbols):
        if (self.expressions is None) == (self.functions is None):
            raise ParameterError("CustomLibrary needs exactly one of expressions= or functions=")
        if self.expressions is not None:
            return self._from_expressions()
        for name, f in self.functions.items():
            if not (isinstance(name, str) and IDENTIFIER.match(name)) or not callable(f):
                raise ParameterError(f"functions must map identifier names to callables; "
                                     f"got {name!r}: {type(f).__name__}")
        self._funcs = [(self.functions[n], j) for n in self.functions for j in range(len(symbols))]
        return [sp.Function(n)(s) for n in self.functions for s in symbols]

    def _from_expressions(self):
        exprs = [adopt(e, self.names_all, label=f"expressions[{i}]")
                 for i, e in enumerate(self.expressions)]
        self._compiled = [compile_numpy(e, self.names_all) for e in exprs]
        return exprs

    def user_functions(self):
        return dict(self.functions or {})

    def fit(self, names):
        self.names_all = list(names)
        return super().fit(names)

    def _select(self, names):
        # expressions name their own variables, so they see all of them
        return list(range(len(names))) if self.expressions is not None else super()._select(names)

    def _evaluate(self, Zs):
        if self.expressions is not None:
            return np.column_stack([f(Zs) for f in self._compiled])
        return np.column_stack([np.asarray(f(Zs[:, j]), dtype=float) for f, j in self._funcs])
