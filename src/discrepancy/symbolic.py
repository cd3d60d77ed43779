"""Sympy expressions as the single source of truth for every term.

Three conversions live here, each a plain tree walk over a whitelist of node
types, so nothing is ever passed to ``eval``/``exec``/``sympify``:

* :func:`compile_numpy` turns an expression into a vectorised numpy callable
  (``sympy.lambdify`` would generate and ``exec`` source code, which we refuse
  for expressions read back from model files);
* :func:`to_data` / :func:`from_data` turn an expression into nested JSON lists
  and back (model files);
* :func:`to_casadi` maps an expression onto CasADi symbols (exact export).
"""
from __future__ import annotations

import re
from collections.abc import Callable, Mapping, Sequence

import numpy as np
import sympy as sp

from .errors import ExportError, ModelFileError
from .expression_tape import CompiledExpressions
from .symbolic_functions import FUNCTIONS, NARY_FUNCTIONS
from .symbolic_functions import finite_number as _number

IDENTIFIER = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")

def symbol(name: str) -> sp.Symbol:
    """The real symbol used for a variable name everywhere in the package."""
    if not isinstance(name, str) or not name:
        from .errors import ParameterError
        raise ParameterError(f"a variable name must be a non-empty string; got {name!r:.80}")
    return sp.Symbol(name, real=True)


def _check_expression(expr, names, label: str, type_error: type, name_error: type) -> None:
    """``type_error`` unless ``expr`` is a sympy expression, ``name_error`` if it uses a
    symbol that is not one of ``names``; ``label`` names the argument."""
    if not isinstance(expr, sp.Basic):
        raise type_error(f"{label} must be a sympy expression; got {type(expr).__name__}")
    unknown = sorted(s.name for s in expr.free_symbols if s.name not in names)
    if unknown:
        raise name_error(f"{label} = {expr} uses {unknown}, which are not among the "
                         f"variables {list(names)}")


def adopt(expr, names: Sequence[str], *, label: str) -> sp.Expr:
    """``expr`` with its symbols replaced by the package's real symbols of the same names.

    Numbers are accepted as constants. Raises ParameterError for a non-sympy object and
    UnknownNameError for a symbol that is not one of ``names``; ``label`` names the argument.
    """
    from .errors import ParameterError, UnknownNameError

    if isinstance(expr, (int, float)) and not isinstance(expr, bool):
        expr = sp.Float(expr) if isinstance(expr, float) else sp.Integer(expr)
    _check_expression(expr, names, label, ParameterError, UnknownNameError)
    return expr.xreplace({s: symbol(s.name) for s in expr.free_symbols})


def compile_numpy(expr: sp.Expr, names: Sequence[str],
                  functions: Mapping[str, Callable] | None = None) -> Callable:
    """Vectorised evaluator of ``expr``: ``f(Z)`` with ``Z`` ``(m, len(names))`` -> ``(m,)``.

    ``functions`` maps names of undefined sympy functions (user numpy terms)
    to numpy callables. The expression runs as a tape of numpy steps, a repeated
    subexpression once (:mod:`~discrepancy.expression_tape`).
    """
    return CompiledExpression(CompiledExpressions([expr], names, functions), expr, list(names),
                              functions)


class CompiledExpression:
    """What :func:`compile_numpy` returns: ``f(Z) -> (m,)``, which pickles (as the
    expression, names and functions it is compiled again from), so fitted models do."""

    def __init__(self, evaluate: Callable, expr, names: list, functions: dict):
        self._evaluate, self._source = evaluate, (expr, names, functions or None)

    def __call__(self, Z):
        return self._evaluate(Z)[0]

    def __reduce__(self):
        return compile_numpy, self._source


def to_data(expr: sp.Expr):
    """Nested JSON-compatible lists for ``expr``.

    Nodes: ``["sym", name]``, ``["num", p, q]``, ``["float", value]``, ``["add", ...]``,
    ``["mul", ...]``, ``["pow", base, exponent]``, ``["fn", name, ...]``.
    """
    if not isinstance(expr, sp.Basic):
        from .errors import ExportError
        raise ExportError(f"expr must be a sympy expression; got {type(expr).__name__}")
    if expr.is_Symbol:
        return ["sym", expr.name]
    if expr in CONSTANTS.values():
        return ["const", str(expr)]
    if expr.is_Rational:
        if max(abs(int(expr.p)), int(expr.q)) <= MAX_INTEGER:
            return ["num", int(expr.p), int(expr.q)]
        return ["float", float(expr)]
    if expr.is_Float or expr.is_number and not expr.args:
        return ["float", float(expr)]
    if expr.is_Add:
        return ["add", *[to_data(a) for a in expr.args]]
    if expr.is_Mul:
        return ["mul", *[to_data(a) for a in expr.args]]
    if expr.is_Pow:
        return ["pow", to_data(expr.args[0]), to_data(expr.args[1])]
    name = type(expr).__name__
    if name in FUNCTIONS or name in NARY_FUNCTIONS or \
            isinstance(expr, sp.core.function.AppliedUndef):
        return ["fn", name, *[to_data(a) for a in expr.args]]
    if expr.is_number:
        return ["float", float(expr)]
    raise ExportError(f"cannot store expression {expr}: node type {name} is not supported")


MAX_INTEGER = 10**30   # integers in stored rationals (larger ones are stored as floats)
CONSTANTS = {"pi": sp.pi, "E": sp.E}
MAX_EXPONENT = 64      # numeric exponents: keeps sympy's exact arithmetic small


class _Reader:
    """Context of one :func:`from_data` call: where the expression is, which user functions
    it may call, and the error to raise."""

    def __init__(self, where: str, functions):
        self.where, self.functions = where, functions

    def bad(self, why: str) -> ModelFileError:
        return ModelFileError(f"{self.where}: {why}; the model file is corrupted or was edited")

    def read(self, data, depth: int) -> sp.Expr:
        if depth > MAX_DEPTH:
            raise self.bad("expression nested too deeply")
        if not isinstance(data, list) or not data or not isinstance(data[0], str):
            raise self.bad(f"expected a list starting with a node name, got "
                           f"{type(data).__name__}")
        reader = _NODE_READERS.get(data[0])
        if reader is None:
            raise self.bad(f"unknown node {data[0]!r:.40}")
        return reader(self, data[1:], depth + 1)

    def bounded(self, expr):
        """Refuse numbers beyond float range (they can only come from a tampered file)."""
        if expr.is_Number and not np.isfinite(float(expr)):
            raise self.bad("a number in the expression is beyond floating-point range")
        return expr


def _read_sym(r, args, depth):
    if len(args) != 1 or not isinstance(args[0], str) or not IDENTIFIER.match(args[0]):
        raise r.bad(f"symbol name must be an identifier, got {args!r:.60}")
    return symbol(args[0])


def _is_int(a) -> bool:
    return isinstance(a, int) and not isinstance(a, bool) and abs(a) <= MAX_INTEGER


def _read_num(r, args, depth):
    if len(args) != 2 or not all(_is_int(a) for a in args) or args[1] == 0:
        raise r.bad(f"rational must be two integers of at most {MAX_INTEGER} with q != 0, "
                    f"got {str(args)[:60]}")
    return sp.Rational(args[0], args[1])


def _read_const(r, args, depth):
    if len(args) != 1 or args[0] not in CONSTANTS:
        raise r.bad(f"constant must be one of {sorted(CONSTANTS)}, got {str(args)[:40]}")
    return CONSTANTS[args[0]]


def _read_float(r, args, depth):
    if len(args) != 1 or isinstance(args[0], bool) or not isinstance(args[0], (int, float)) \
            or not np.isfinite(args[0]):
        raise r.bad(f"float must be one finite number, got {args!r:.60}")
    return sp.Float(args[0])


def _read_sum_or_product(op):
    def read(r, args, depth):
        if len(args) < 2:
            raise r.bad(f"{op.__name__.lower()} needs at least two operands")
        return r.bounded(op(*[r.read(a, depth) for a in args]))
    return read


def _read_pow(r, args, depth):
    if len(args) != 2:
        raise r.bad("pow needs a base and an exponent")
    base, exponent = r.read(args[0], depth), r.read(args[1], depth)
    if exponent.is_number and not (exponent.is_Rational and abs(exponent.p) <= MAX_EXPONENT
                                   and exponent.q <= MAX_EXPONENT
                                   or exponent.is_Float and abs(exponent) <= MAX_EXPONENT):
        raise r.bad(f"numeric exponents must be at most {MAX_EXPONENT} in size")
    return r.bounded(sp.Pow(base, exponent))


def _read_fn(r, args, depth):
    if not args or not isinstance(args[0], str) or not IDENTIFIER.match(args[0]):
        raise r.bad(f"function name must be an identifier, got {args[:1]!r:.60}")
    name, fargs = args[0], [r.read(a, depth) for a in args[1:]]
    if name in FUNCTIONS:
        if len(fargs) != 1:
            raise r.bad(f"{name} takes one argument, got {len(fargs)}")
        return r.bounded(FUNCTIONS[name][0](fargs[0]))
    if name in NARY_FUNCTIONS:
        if len(fargs) < 2:
            raise r.bad(f"{name} takes at least two arguments, got {len(fargs)}")
        return r.bounded(NARY_FUNCTIONS[name][0](*fargs))
    if r.functions is not None and name not in r.functions:
        raise r.bad(f"function {name!r} is neither built in nor a declared user function")
    if not fargs:
        raise r.bad(f"user function {name!r} needs at least one argument")
    return sp.Function(name)(*fargs)


_NODE_READERS = {"sym": _read_sym, "num": _read_num, "const": _read_const, "float": _read_float,
                 "add": _read_sum_or_product(sp.Add), "mul": _read_sum_or_product(sp.Mul),
                 "pow": _read_pow, "fn": _read_fn}
MAX_DEPTH = 64


def from_data(data, *, where: str = "expression",
              functions: Sequence[str] | None = None) -> sp.Expr:
    """Rebuild an expression from :func:`to_data` output, refusing anything else.

    One reader per node type (``_NODE_READERS``); ``functions`` lists the user function
    names allowed in ``fn`` nodes (``None``: any). Numbers are bounded, so a small tampered
    file cannot make sympy compute huge integers.
    """
    return _Reader(where, functions).read(data, 0)


def to_casadi(expr: sp.Expr, variables: Mapping[str, object], *, term: str | None = None):
    """The CasADi expression of ``expr`` with symbols replaced by ``variables[name]`` (SX/MX)."""
    from ._optional import require

    ca = require("casadi", purpose="exporting to CasADi")
    _check_expression(expr, list(variables), term or "expr", ExportError, ExportError)

    def build(e):
        if e.is_Symbol:
            return variables[e.name]
        if e.is_number:
            return _number(e)
        args = [build(a) for a in e.args]
        if e.is_Add:
            out = args[0]
            for a in args[1:]:
                out = out + a
            return out
        if e.is_Mul:
            out = args[0]
            for a in args[1:]:
                out = out * a
            return out
        if e.is_Pow:
            return args[0] ** args[1]
        name = type(e).__name__
        if name in FUNCTIONS and FUNCTIONS[name][2]:
            return getattr(ca, FUNCTIONS[name][2])(args[0])
        if name in NARY_FUNCTIONS:
            out = args[0]
            for a in args[1:]:
                out = getattr(ca, NARY_FUNCTIONS[name][2])(out, a)
            return out
        raise ExportError(f"term {term or e} cannot be exported to CasADi: {name} is a "
                          "numpy-only function with no symbolic form; use sympy expressions "
                          "(e.g. CustomLibrary(expressions=[...])) for terms you want to export")

    return build(expr)


class _NamePrinter(sp.printing.str.StrPrinter):
    """PySINDy-style names: ``x1^2 x2``, ``sin(x1)``, ``sin(x1) u``; factors in variable order."""

    def __init__(self, names: Sequence[str] = ()):
        super().__init__()
        self._rank = {n: i for i, n in enumerate(names)}

    def _key(self, factor):
        ranks = [self._rank.get(s.name, len(self._rank)) for s in factor.free_symbols]
        return (min(ranks, default=-1), not (factor.is_Symbol or factor.is_Pow), str(factor))

    def _print_Mul(self, expr):
        coeff, factors = expr.as_coeff_mul()
        factors = sorted(factors, key=self._key)
        body = " ".join(self._print(f) if not f.is_Add else f"({self._print(f)})" for f in factors)
        if coeff == 1:
            return body
        return f"-{body}" if coeff == -1 else f"{self._print(coeff)} {body}"

    def _print_Pow(self, expr):
        base, ex = expr.args
        if ex == sp.S.Half:
            return f"sqrt({self._print(base)})"
        b = self._print(base)
        if not (base.is_Symbol or base.is_Function):
            b = f"({b})"
        return f"{b}^{self._print(ex)}"


def feature_name(expr: sp.Expr, names: Sequence[str] = ()) -> str:
    """Readable name of a library column, e.g. ``x1^2 x2``; factors ordered as ``names``."""
    return _NamePrinter(names).doprint(expr)
