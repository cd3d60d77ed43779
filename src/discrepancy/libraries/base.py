"""Feature libraries Θ(z) on the variables z = [x, u].

Every column carries its sympy expression, so a fitted model is an exact formula.
Libraries compose: ``a + b`` concatenates columns, ``a * b`` forms all products
(``sin(x) * u``); duplicate columns (same expression) are dropped once, so a
composite library never has two identical columns.
"""
from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Sequence

import numpy as np
import sympy as sp

from ..base import Estimator
from ..constraints import InstanceOf, Predicate
from ..data.validation import as_float_array
from ..errors import NotFittedError, ParameterError, ShapeError, UnknownNameError, describe
from ..resources import check_features
from ..symbolic import IDENTIFIER, feature_name, symbol

#: ``variables=``: ``None`` (all) or a list of names / indices into ``z = [x, u]``
VARIABLES = [None, Predicate(lambda v: isinstance(v, (list, tuple)) and len(v) > 0 and all(
    isinstance(e, (str, int, np.integer)) and not isinstance(e, bool) for e in v),
    "a non-empty list of variable names or indices")]


class FeatureLibrary(Estimator, ABC):
    """Base of all libraries: ``fit(names)`` then ``transform(Z)``.

    ``fit`` takes the names of all variables ``z = [states..., inputs...]`` and
    sets ``feature_expressions_`` (list of sympy expressions, one per column)
    and ``n_features_``. ``transform`` maps ``Z`` ``(m, len(names))`` to Θ
    ``(m, n_features_)``.
    """

    def __add__(self, other: FeatureLibrary) -> FeatureLibrary:
        _check_operand("added to", other)
        return ConcatLibrary([self, other])

    def __mul__(self, other: FeatureLibrary) -> FeatureLibrary:
        _check_operand("multiplied by", other)
        return TensorLibrary(self, other)

    @abstractmethod
    def fit(self, names: Sequence[str]) -> FeatureLibrary:
        """Bind the library to variable names; returns self."""

    @abstractmethod
    def _transform(self, Z: np.ndarray) -> np.ndarray:
        """Hook: Θ for validated ``Z``."""

    def transform(self, Z: np.ndarray, *, out: np.ndarray | None = None) -> np.ndarray:
        """Θ ``(m, n_features_)`` for ``Z`` ``(m, n_variables)`` (float64, finite).

        ``out``: optional float64 ``(m, n_features_)`` array to write Θ into (returned).
        The blocked Gram accumulation reuses one such buffer per block: fresh 2 MB
        arrays cost a page fault per 4 kB, which measured 10x the arithmetic.
        """
        if not hasattr(self, "feature_expressions_"):
            raise NotFittedError(f"{type(self).__name__}.transform called before fit(names)")
        Z = as_float_array("Z", Z)
        if Z.ndim != 2 or Z.shape[1] != len(self.names_):
            raise ShapeError(f"Z must be (m, {len(self.names_)}) for variables {self.names_}; "
                             f"got shape {Z.shape}")
        if out is None:
            return self._transform(Z)
        if out.shape != (Z.shape[0], self.n_features_) or out.dtype != np.float64:
            raise ShapeError(f"out must be float64 of shape {(Z.shape[0], self.n_features_)}; "
                             f"got {out.dtype} {out.shape}")
        return self._transform_into(Z, out)

    def _transform_into(self, Z: np.ndarray, out: np.ndarray) -> np.ndarray:
        """Hook: write Θ into ``out``; libraries that can skip the temporary override it."""
        out[...] = self._transform(Z)
        return out

    def user_functions(self) -> dict:
        """Numpy functions of the library's custom terms, by name (empty for exact terms)."""
        return {}

    def fit_transform(self, Z: np.ndarray) -> np.ndarray:
        """Θ of data ``Z`` ``(m, k)``, the library fitted to its ``k`` columns (default names
        ``x1 ... xk``), as PySINDy's ``fit_transform``."""
        return self.fit(as_float_array("Z", Z)).transform(Z)

    def get_feature_names(self) -> list[str]:
        """Names of the ``p`` columns of Θ in column order (e.g. ``"x1^2 x2"``); needs a fit."""
        if not hasattr(self, "feature_expressions_"):
            raise NotFittedError(f"{type(self).__name__}.get_feature_names called before fit")
        return [feature_name(e, self.names_) for e in self.feature_expressions_]

    def _bind(self, names: Sequence[str], expressions: list[sp.Expr]) -> None:
        if not expressions:
            raise ParameterError(f"{self!r} produces no features for variables {list(names)}; "
                                 "the library must have at least one column")
        check_features(repr(self), len(expressions))
        self.names_ = list(names)
        self.feature_expressions_ = expressions
        self.n_features_ = len(expressions)


def check_names(names) -> list[str]:
    """The variable names a library is fitted to: a list of distinct identifiers, or data
    ``(m, k)`` as PySINDy's libraries are fitted (then the default names ``x1 ... xk``)."""
    if isinstance(names, np.ndarray) and names.ndim == 2 and names.dtype.kind in "iuf":
        return [f"x{i + 1}" for i in range(names.shape[1])]
    if isinstance(names, str) or not isinstance(names, (list, tuple)) or not all(
            isinstance(n, str) and IDENTIFIER.match(n) for n in names) or \
            len(set(names)) != len(names):
        raise ShapeError(f"names must be a list of distinct identifiers (one per variable); "
                         f"got {describe(names)}")
    return list(names)


def _check_operand(verb: str, other) -> None:
    if not isinstance(other, FeatureLibrary):
        raise ParameterError(f"libraries can only be {verb} libraries; got "
                             f"{type(other).__name__}")


class BaseLibrary(FeatureLibrary):
    """A library acting on a chosen subset of the variables.

    Args:
        variables: names or indices (into z = [x, u]) the library acts on; ``None`` = all.
    """

    _parameter_constraints = {"variables": VARIABLES}

    def __init__(self, *, variables: Sequence[str | int] | None = None):
        self.variables = variables

    def _select(self, names: Sequence[str]) -> list[int]:
        if self.variables is None:
            return list(range(len(names)))
        chosen = []
        for v in self.variables:
            if isinstance(v, (int, np.integer)) and 0 <= v < len(names):
                chosen.append(int(v))
            elif isinstance(v, str) and v in names:
                chosen.append(list(names).index(v))
            else:
                raise UnknownNameError(f"variables of {type(self).__name__} must be names or "
                                       f"indices of {list(names)}; got {v!r}")
        return chosen

    def fit(self, names: Sequence[str]) -> BaseLibrary:
        self._validate_params()
        names = check_names(names)
        self._index = self._select(names)
        count = self._n_features(len(self._index))
        if count is not None:  # counted before any expression is built
            check_features(f"{self!r} of {len(self._index)} variables", count)
        symbols = [symbol(names[i]) for i in self._index]
        self._bind(names, self._expressions(symbols))
        return self

    def _transform(self, Z):
        return self._evaluate(Z[:, self._index])

    def _transform_into(self, Z, out):
        return self._evaluate_into(Z[:, self._index], out)

    def _evaluate_into(self, Zs: np.ndarray, out: np.ndarray) -> np.ndarray:
        out[...] = self._evaluate(Zs)
        return out

    def _n_features(self, k: int) -> int | None:
        """Hook: the number of columns on ``k`` variables, counted without building them
        (``None``: no faster than building them)."""
        return None

    @abstractmethod
    def _expressions(self, symbols: list[sp.Symbol]) -> list[sp.Expr]:
        """Hook: the column expressions for the selected variables."""

    @abstractmethod
    def _evaluate(self, Zs: np.ndarray) -> np.ndarray:
        """Hook: the columns for the selected variables ``Zs`` (m, k)."""


def _unique(expressions: list[sp.Expr]) -> list[int]:
    seen, keep = set(), []
    for i, e in enumerate(expressions):
        if e not in seen:
            seen.add(e)
            keep.append(i)
    return keep


class ConcatLibrary(FeatureLibrary):
    """Columns of several libraries side by side (``a + b``), duplicates dropped."""

    _parameter_constraints = {"libraries": [Predicate(
        lambda v: isinstance(v, (list, tuple)) and v and all(isinstance(e, FeatureLibrary)
                                                             for e in v),
        "a non-empty list of feature libraries")]}

    def __init__(self, libraries: Sequence[FeatureLibrary]):
        self.libraries = libraries

    def _parts(self) -> list[FeatureLibrary]:
        """The libraries, nested sums flattened."""
        return [p for lib in self.libraries
                for p in (lib._parts() if isinstance(lib, ConcatLibrary) else [lib])]

    def fit(self, names):
        self._validate_params()
        names = check_names(names)
        self._fitted_parts = self._parts()
        exprs = [e for lib in self._fitted_parts for e in lib.fit(names).feature_expressions_]
        self._keep = _unique(exprs)
        self._bind(names, [exprs[i] for i in self._keep])
        return self

    def user_functions(self):
        return {k: v for lib in self._parts() for k, v in lib.user_functions().items()}

    def _transform(self, Z):
        theta = np.hstack([lib._transform(Z) for lib in self._fitted_parts])
        return theta if len(self._keep) == theta.shape[1] else theta[:, self._keep]


class TensorLibrary(FeatureLibrary):
    """All products of a column of ``left`` and a column of ``right`` (``left * right``)."""

    _parameter_constraints = {"left": [InstanceOf(FeatureLibrary, "a feature library")],
                              "right": [InstanceOf(FeatureLibrary, "a feature library")]}

    def __init__(self, left: FeatureLibrary, right: FeatureLibrary):
        self.left = left
        self.right = right

    def fit(self, names):
        self._validate_params()
        names = check_names(names)
        a = self.left.fit(names).feature_expressions_
        b = self.right.fit(names).feature_expressions_
        check_features(repr(self), len(a) * len(b))
        exprs = [ea * eb for ea in a for eb in b]
        self._keep = _unique(exprs)
        self._bind(names, [exprs[i] for i in self._keep])
        return self

    def user_functions(self):
        return {**self.left.user_functions(), **self.right.user_functions()}

    def _transform(self, Z):
        a, b = self.left._transform(Z), self.right._transform(Z)
        theta = (a[:, :, None] * b[:, None, :]).reshape(Z.shape[0], -1)
        return theta if len(self._keep) == theta.shape[1] else theta[:, self._keep]
