"""The prior model f_m(x, u): a vectorised callable, sympy expressions, or nothing."""
from __future__ import annotations

import inspect
from collections.abc import Callable, Sequence

import numpy as np
import sympy as sp

from ..errors import ExportError, ParameterError, PriorError, describe
from ..symbolic import adopt, compile_numpy


class Prior:
    """Evaluates a prior on ``x`` ``(m, n)`` and ``u`` ``(m, r)`` or ``None``, checking its output.

    Args:
        prior: ``None`` (plain SINDy), a callable ``f_m(x, u) -> (m, n)`` (or ``f_m(x)``),
            or a sequence of ``n`` sympy expressions in the state and input symbols.
        state_names, input_names: variable names the expressions refer to.
    """

    def __init__(self, prior, state_names: Sequence[str], input_names: Sequence[str]):
        self.n = len(state_names)
        self.names = [*state_names, *input_names]
        self.expressions: list[sp.Expr] | None = None
        self._call: Callable | None = None
        if prior is None:
            return
        if callable(prior) and not isinstance(prior, sp.Basic):
            self._call = _adapt(prior)
        elif isinstance(prior, (list, tuple, sp.MatrixBase)):
            self.expressions = self._check_expressions(list(prior))
            self._terms = [self._compiled(i, e) for i, e in enumerate(self.expressions)]
            self._call = self._evaluate_expressions
        else:
            raise ParameterError("prior must be None, a callable f_m(x, u) or a list of "
                                 f"{self.n} sympy expressions; got {type(prior).__name__}")

    def _check_expressions(self, exprs):
        if len(exprs) != self.n:
            raise ParameterError(f"prior must have one expression per state ({self.n}); "
                                 f"got {len(exprs)}")
        return [adopt(e, self.names, label=f"prior[{i}]") for i, e in enumerate(exprs)]

    def _compiled(self, i: int, expr: sp.Expr):
        try:
            return compile_numpy(expr, self.names)
        except ExportError as e:
            raise PriorError(f"prior[{i}] = {expr} cannot be evaluated: {e}") from None

    def _evaluate_expressions(self, x, u):
        z = x if u is None else np.hstack([x, u])
        return np.column_stack([f(z) for f in self._terms])

    @property
    def is_symbolic(self) -> bool:
        """True when the prior is given as sympy expressions (then the whole hybrid model exports).
        """
        return self.expressions is not None

    def unchecked(self, x: np.ndarray, u: np.ndarray | None) -> np.ndarray:
        """``f_m(x, u)`` where non-finite values are allowed (a forecast that left the
        prior's domain, e.g. a negative tank level under a square root; call it inside
        ``np.errstate(all="ignore")``); errors still raise PriorError."""
        if self._call is None:
            return np.zeros_like(x)
        try:
            return np.asarray(self._call(x, u), dtype=float).reshape(x.shape)
        except Exception as e:
            raise PriorError(f"prior raised {type(e).__name__}: {e} when called with x of shape "
                             f"{x.shape} and u {None if u is None else u.shape}") from e

    def __call__(self, x: np.ndarray, u: np.ndarray | None) -> np.ndarray:
        """``f_m(x, u)`` ``(m, n)``; zeros for no prior. Raises PriorError on bad output."""
        if self._call is None:
            return np.zeros_like(x)
        try:
            out = self._call(x, u)
        except Exception as e:
            raise PriorError(f"prior raised {type(e).__name__}: {e} when called with x of shape "
                             f"{x.shape} and u {None if u is None else u.shape}") from e
        if np.iscomplexobj(out):
            raise PriorError("prior must return real values; it returned complex ones (the "
                             "imaginary part would be dropped)")
        try:
            out = np.asarray(out, dtype=float)
        except (TypeError, ValueError) as e:
            raise PriorError(f"prior must return a numeric array of shape {x.shape}; it "
                             f"returned {describe(out)} ({e})") from None
        if out.shape != x.shape:
            raise PriorError(f"prior must return an array of shape {x.shape} (same as x); "
                             f"got shape {out.shape}")
        if not np.all(np.isfinite(out)):
            row = int(np.argwhere(~np.isfinite(out))[0][0])
            raise PriorError(f"prior returned non-finite values (first at row {row}, "
                             f"x = {x[row]})")
        return out


def _adapt(f: Callable) -> Callable:
    """Call ``f(x, u)``, or ``f(x)`` when it takes a single argument."""
    try:
        params = [p for p in inspect.signature(f).parameters.values()
                  if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD, p.VAR_POSITIONAL)]
    except (TypeError, ValueError):
        return f
    if len(params) == 1 and params[0].kind != params[0].VAR_POSITIONAL:
        return _StatesOnly(f)
    return f


class _StatesOnly:
    """``f(x, u) -> f(x)`` for a prior of the states alone (a class, so it pickles)."""

    def __init__(self, f: Callable):
        self.f = f

    def __call__(self, x, u):
        return self.f(x)
