"""Custom library: user sympy expressions (exact) or named numpy functions."""
from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import numpy as np
import sympy as sp

from ..constraints import Predicate
from ..errors import FeatureError, ParameterError, describe
from ..symbolic import FUNCTIONS, IDENTIFIER, adopt, compile_numpy
from .base import VARIABLES, BaseLibrary


def _is_function_map(value) -> bool:
    return isinstance(value, Mapping) and bool(value) and all(
        isinstance(k, str) and IDENTIFIER.match(k) and callable(f) for k, f in value.items())


class CustomLibrary(BaseLibrary):
    """Columns given by the user.

    ``expressions``: sympy expressions in the variables (build symbols with
    :func:`discrepancy.symbolic.symbol`, or any sympy Symbol with the variable's name);
    exact, and exported to sympy, LaTeX and CasADi. They may call undefined sympy
    functions (``sympy.Function("sat")(x1)``) whose numpy implementations are given in
    ``functions``.

    ``functions`` alone: a mapping ``name -> vectorised numpy function of one array``
    applied to each chosen variable (columns ``name(x1)``, ...). Such terms have no
    symbolic form: they are not exported to CasADi, and must be passed again to
    :func:`discrepancy.load_model`.

    Args:
        expressions: sequence of sympy expressions.
        functions: mapping of identifier names to vectorised numpy callables; names must
            not shadow the built-in functions (``sin``, ``log``, ...).
        variables: variables the functions act on (names or indices); ``None`` = all.
    """

    _parameter_constraints = {
        "expressions": [None, Predicate(lambda v: isinstance(v, (list, tuple)) and len(v) > 0,
                                        "a non-empty list of sympy expressions")],
        "functions": [None, Predicate(_is_function_map,
                                      "a non-empty mapping of identifier names to callables")],
        "variables": VARIABLES,
    }

    def __init__(self, expressions: Sequence[sp.Expr] | None = None, *,
                 functions: Mapping[str, Callable] | None = None, variables=None):
        super().__init__(variables=variables)
        self.expressions = expressions
        self.functions = functions

    def _check_params(self):
        if self.expressions is None and self.functions is None:
            raise ParameterError("CustomLibrary needs expressions=, functions= or both")
        shadowed = sorted(set(self.functions or {}) & set(FUNCTIONS))
        if shadowed:
            raise ParameterError(f"CustomLibrary: functions {shadowed} would shadow the built-in "
                                 "functions of that name; give them other names (e.g. 'log1p')")

    def fit(self, names):
        self._names_all = list(names)
        return super().fit(names)

    def _select(self, names):
        # expressions name their own variables, so they see all of them
        return list(range(len(names))) if self.expressions is not None else super()._select(names)

    def _expressions(self, symbols):
        if self.expressions is not None:
            exprs = [adopt(e, self._names_all, label=f"expressions[{i}]")
                     for i, e in enumerate(self.expressions)]
            self._compiled = [compile_numpy(e, self._names_all, self.functions) for e in exprs]
            return exprs
        self._funcs = [(self.functions[n], j) for n in self.functions for j in range(len(symbols))]
        return [sp.Function(n)(s) for n in self.functions for s in symbols]

    def user_functions(self):
        return dict(self.functions or {})

    def _evaluate(self, Zs):
        if self.expressions is not None:
            calls = [(lambda f=f: f(Zs)) for f in self._compiled]
        else:
            calls = [(lambda f=f, j=j: f(Zs[:, j])) for f, j in self._funcs]
        m = Zs.shape[0]
        return np.column_stack([self._column(call, name, m) for call, name in
                                zip(calls, self.get_feature_names(), strict=True)])

    @staticmethod
    def _column(call, name: str, m: int) -> np.ndarray:
        """One column ``(m,)`` from the user's function, or FeatureError naming the term."""
        try:
            value = call()
        except Exception as e:
            raise FeatureError(f"library term {name!r} raised {type(e).__name__}: {e} (on "
                               f"{m} rows)") from e
        if np.iscomplexobj(value):
            raise FeatureError(f"library term {name!r} returned complex values; terms must be "
                               "real")
        try:
            return np.broadcast_to(np.asarray(value, dtype=float), (m,))
        except (TypeError, ValueError):
            raise FeatureError(f"library term {name!r} must return {m} numbers (one per "
                               f"row); got {describe(value)}") from None
