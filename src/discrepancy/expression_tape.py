"""Sympy expressions evaluated on numpy rows by a flat tape of steps (what
:func:`~discrepancy.symbolic.compile_numpy` and
:func:`~discrepancy.expression_tape.compile_numpy_many` return).

A tree walk compiles the expressions once into a list of steps, each one numpy call on the
values of earlier steps: a subexpression that occurs several times (in one expression or
across several compiled together, e.g. ``sin(φ₁ - φ₂)`` in every entry of a mass matrix) is
one step, computed once per call. Every step is the numpy operation the tree would apply
to the same operands in the same order (sums and products folded left to right, ``x**2``
as ``np.square``), so the values are bit for bit those of a direct tree walk; numbers
inside sums and products enter as float64 scalars (``+`` and ``×`` round the same with a
scalar as with an array of it) instead of a fresh ``np.full`` per call. A user function
(an undefined sympy function given as a numpy callable) is called once per occurrence, as
written. Written by hand: ``sympy.lambdify`` would generate and ``exec`` source code,
which we refuse for expressions read back from model files, and its ``cse`` does the same.
"""
from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import numpy as np
import sympy as sp

from .errors import ExportError, FeatureError
from .symbolic_functions import FUNCTIONS, NARY_FUNCTIONS, finite_number


class _Builder:
    """Turns expressions into steps ``step(values, Z) -> array``, one per distinct node."""

    def __init__(self, names: Sequence[str], functions: Mapping[str, Callable]):
        self.index = {n: i for i, n in enumerate(names)}
        self.names, self.functions = list(names), dict(functions)
        self.steps: list[Callable] = []
        self.slots: dict = {}

    def _add(self, key, step) -> int:
        if key not in self.slots:
            self.slots[key] = len(self.steps)
            self.steps.append(step)
        return self.slots[key]

    def constant(self, e) -> float:
        return np.float64(finite_number(e))

    def operand(self, e):
        """A sum's or product's operand: ``(True, float64)`` for a number, else
        ``(False, slot)``."""
        return (True, self.constant(e)) if e.is_number else (False, self.slot(e))

    def slot(self, e) -> int:
        """The slot of the step computing ``e`` ``(m,)``."""
        if e.is_Symbol:
            if e.name not in self.index:
                raise ExportError(f"expression uses variable {e.name!r}, not one of "
                                  f"{self.names}")
            i = self.index[e.name]
            return self._add(("symbol", i), lambda v, Z: Z[:, i])
        if e.is_number:
            c = float(self.constant(e))
            return self._add(("number", c.hex()), lambda v, Z: np.full(Z.shape[0], c))
        if e.is_Add or e.is_Mul:
            ops = [self.operand(a) for a in e.args]
            key = ("add" if e.is_Add else "mul", tuple((c, float(x).hex() if c else x)
                                                       for c, x in ops))
            return self._add(key, _fold(np.add if e.is_Add else np.multiply, ops))
        if e.is_Pow:
            return self._power(e)
        name = type(e).__name__
        if name in FUNCTIONS:
            f, a = FUNCTIONS[name][1], self.slot(e.args[0])
            return self._add((name, a), lambda v, Z: f(v[a]))
        if name in NARY_FUNCTIONS:
            ops = [(False, self.slot(a)) for a in e.args]
            return self._add((name, tuple(s for _, s in ops)),
                             _fold(NARY_FUNCTIONS[name][1], ops))
        if isinstance(e, sp.core.function.AppliedUndef) and name in self.functions:
            call = _user_call(name, self.functions[name], [self.slot(a) for a in e.args])
            return self._add(("call", len(self.steps)), call)
        raise ExportError(f"cannot evaluate {e} numerically: {name} is not a supported function "
                          f"(supported: {', '.join(sorted(FUNCTIONS))}, or user functions "
                          f"{sorted(self.functions)})")

    def _power(self, e) -> int:
        base, ex = self.slot(e.args[0]), e.args[1]
        if ex.is_Integer and int(ex) == 2:
            return self._add(("square", base), lambda v, Z: np.square(v[base]))
        if ex.is_number:
            p = float(self.constant(ex))
            return self._add(("power", base, p.hex()), lambda v, Z: np.power(v[base], p))
        exponent = self.slot(ex)
        return self._add(("power", base, exponent),
                         lambda v, Z: np.power(v[base], v[exponent]))


def _user_call(name: str, f: Callable, slots: list[int]) -> Callable:
    """The step ``f(*values of slots)`` for a user's numpy function, its failures named
    (FeatureError)."""
    def call(v, Z):
        try:
            value = f(*[v[s] for s in slots])
        except Exception as e:
            raise FeatureError(f"user function {name!r} raised {type(e).__name__}: {e}") from e
        if np.iscomplexobj(value):
            raise FeatureError(f"user function {name!r} returned complex values")
        try:
            return np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            raise FeatureError(f"user function {name!r} must return numbers; got "
                               f"{type(value).__name__}") from None
    return call


def _fold(op, operands) -> Callable:
    """``op(op(a0, a1), a2)...`` over the operands (numbers inline, slots looked up)."""
    if len(operands) == 2:
        (c0, a), (c1, b) = operands
        if not c0 and not c1:
            return lambda v, Z: op(v[a], v[b])
        if c0 and not c1:
            return lambda v, Z: op(a, v[b])
        if c1 and not c0:
            return lambda v, Z: op(v[a], b)

    def fold(v, Z):
        c, x = operands[0]
        out = x if c else v[x]
        for c, x in operands[1:]:
            out = op(out, x if c else v[x])
        return out
    return fold


class CompiledExpressions:
    """``f(Z) -> [(m,) per expression]`` for rows ``Z`` ``(m, len(names))``; pickles as
    the expressions, names and functions it is compiled again from."""

    def __init__(self, exprs: Sequence[sp.Expr], names: Sequence[str],
                 functions: Mapping[str, Callable] | None = None):
        for expr in exprs:
            if not isinstance(expr, sp.Basic):
                raise ExportError(f"expected a sympy expression, got {type(expr).__name__}")
        builder = _Builder(names, functions or {})
        self.outputs = [builder.slot(e) for e in exprs]
        self._steps = builder.steps
        # an expression asked for twice gets its own array (a copy) at its later places
        self._copied = [self.outputs.index(s) != i for i, s in enumerate(self.outputs)]
        self._repeated = any(self._copied)
        self._source = (list(exprs), list(names), dict(functions) if functions else None)

    def __call__(self, Z) -> list[np.ndarray]:
        values: list = []
        append = values.append
        for step in self._steps:
            append(step(values, Z))
        if self._repeated:
            return [values[s].copy() if copied else values[s]
                    for s, copied in zip(self.outputs, self._copied, strict=True)]
        return [values[s] for s in self.outputs]

    def __reduce__(self):
        return compile_numpy_many, self._source


def compile_numpy_many(exprs: Sequence[sp.Expr], names: Sequence[str],
                       functions: Mapping[str, Callable] | None = None) -> CompiledExpressions:
    """Vectorised evaluator of several expressions sharing their common subexpressions:
    ``f(Z)`` with ``Z`` ``(m, len(names))`` -> a list of ``(m,)`` arrays (a bare symbol
    gives a view of its column of ``Z``); ``functions`` maps names of undefined sympy
    functions (user numpy terms) to numpy callables."""
    return CompiledExpressions(exprs, names, functions)
