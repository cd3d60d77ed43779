"""The functions an expression may use, and its numbers: what every conversion of
:mod:`~discrepancy.symbolic` and the numpy evaluator (:mod:`~discrepancy.expression_tape`)
accept."""
from __future__ import annotations

from collections.abc import Callable

import numpy as np
import sympy as sp

from .errors import ExportError

# name -> (sympy constructor, numpy function, casadi function name)
FUNCTIONS: dict[str, tuple[Callable, Callable, str | None]] = {
    "sin": (sp.sin, np.sin, "sin"), "cos": (sp.cos, np.cos, "cos"),
    "tan": (sp.tan, np.tan, "tan"), "exp": (sp.exp, np.exp, "exp"),
    "log": (sp.log, np.log, "log"), "tanh": (sp.tanh, np.tanh, "tanh"),
    "sinh": (sp.sinh, np.sinh, "sinh"), "cosh": (sp.cosh, np.cosh, "cosh"),
    "atan": (sp.atan, np.arctan, "atan"), "asin": (sp.asin, np.arcsin, "asin"),
    "acos": (sp.acos, np.arccos, "acos"), "Abs": (sp.Abs, np.abs, "fabs"),
    "sign": (sp.sign, np.sign, "sign"),
}
# functions of two or more arguments (saturations, clipping): same triple, applied pairwise
NARY_FUNCTIONS: dict[str, tuple[Callable, Callable, str]] = {
    "Min": (sp.Min, np.minimum, "fmin"), "Max": (sp.Max, np.maximum, "fmax"),
}


def finite_number(expr) -> float:
    """The value of a sympy number; ExportError unless it is finite and real."""
    value = complex(expr)
    if value.imag != 0 or not np.isfinite(value.real):
        raise ExportError(f"the constant {expr} is not a finite real number")
    return value.real
