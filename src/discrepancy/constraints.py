"""Declared parameter constraints, checked where the parameters are used.

Every public class lists what each constructor argument may be, once, in
``_parameter_constraints`` (the scikit-learn ``_param_validation`` idea, written small)::

    _parameter_constraints = {
        "degree": [Interval(Integral, 0, None)],
        "variables": [None, InstanceOf((list, tuple), "a list of names or indices")],
    }

A value is valid when it satisfies any constraint of its list. :func:`validate_params`
raises :class:`~discrepancy.errors.ParameterError` naming the class, the argument, what
was expected and what was given. Checks that tie several arguments together stay in the
class (``Estimator._check_params``).
"""
from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable, Iterable, Mapping
from numbers import Integral, Real

import numpy as np

from .errors import ParameterError, describe

__all__ = ["Constraint", "InstanceOf", "Integral", "Interval", "Options", "Predicate", "Real",
           "check_argument", "is_callable", "make_constraint", "validate_params"]


class Constraint(ABC):
    """One acceptable kind of value; ``str(c)`` says which, for error messages."""

    @abstractmethod
    def is_satisfied_by(self, value) -> bool:
        """Whether ``value`` is acceptable."""

    @abstractmethod
    def __str__(self) -> str:
        """What the constraint accepts, as a noun phrase ("an integer >= 1")."""


def _is_number(value, kind) -> bool:
    if isinstance(value, (bool, np.bool_)):
        return False
    if kind is Integral:
        return isinstance(value, (Integral, np.integer))
    return isinstance(value, (Real, np.integer, np.floating))


class Interval(Constraint):
    """A number of ``kind`` (``Integral`` or ``Real``) between ``low`` and ``high``.

    ``None`` leaves a side open; ``closed`` is ``"both"``, ``"left"``, ``"right"`` or
    ``"neither"``. Reals must be finite unless ``allow_inf``; booleans are never numbers.
    """

    def __init__(self, kind, low=None, high=None, *, closed: str = "both",
                 allow_inf: bool = False):
        if kind not in (Integral, Real) or closed not in ("both", "left", "right", "neither"):
            raise ValueError(f"bad Interval({kind}, closed={closed!r})")
        self.kind, self.low, self.high, self.closed = kind, low, high, closed
        self.allow_inf = allow_inf

    def is_satisfied_by(self, value) -> bool:
        if not _is_number(value, self.kind):
            return False
        v = float(value)
        if np.isnan(v) or (np.isinf(v) and not self.allow_inf):
            return False
        left = self.closed in ("both", "left")
        right = self.closed in ("both", "right")
        if self.low is not None and (v < self.low or (v == self.low and not left)):
            return False
        return not (self.high is not None and (v > self.high or (v == self.high and not right)))

    def __str__(self) -> str:
        noun = "an integer" if self.kind is Integral else "a finite number"
        if self.kind is Real and self.allow_inf:
            noun = "a number"
        parts = []
        if self.low is not None:
            parts.append((">= " if self.closed in ("both", "left") else "> ") + f"{self.low:g}")
        if self.high is not None:
            parts.append(("<= " if self.closed in ("both", "right") else "< ") + f"{self.high:g}")
        return noun + (" " + " and ".join(parts) if parts else "")


class Options(Constraint):
    """One of a fixed set of values (compared with ``==``, type-exact for strings)."""

    def __init__(self, options: Iterable):
        self.options = tuple(options)

    def is_satisfied_by(self, value) -> bool:
        return any(type(value) is type(o) and value == o for o in self.options)

    def __str__(self) -> str:
        return "one of " + ", ".join(repr(o) for o in self.options)


class InstanceOf(Constraint):
    """An instance of ``types``, described as ``description`` (default: the type names)."""

    def __init__(self, types, description: str | None = None):
        self.types = types if isinstance(types, tuple) else (types,)
        self.description = description

    def is_satisfied_by(self, value) -> bool:
        return isinstance(value, self.types) and not isinstance(value, (bool, np.bool_)) \
            or bool in self.types and isinstance(value, (bool, np.bool_))

    def __str__(self) -> str:
        if self.description:
            return self.description
        return "an instance of " + " or ".join(t.__name__ for t in self.types)


class Predicate(Constraint):
    """Any value for which ``test(value)`` is true, described as ``description``."""

    def __init__(self, test: Callable[[object], bool], description: str):
        self.test, self.description = test, description

    def is_satisfied_by(self, value) -> bool:
        try:
            return bool(self.test(value))
        except Exception:  # a predicate that fails on a value rejects it
            return False

    def __str__(self) -> str:
        return self.description


class _NoneConstraint(Constraint):
    def is_satisfied_by(self, value) -> bool:
        return value is None

    def __str__(self) -> str:
        return "None"


#: the constraint "a callable" (priors, user functions)
is_callable = Predicate(callable, "a callable")
boolean = InstanceOf(bool, "True or False")


def make_constraint(spec) -> Constraint:
    """A Constraint from a shorthand: ``None``, ``bool``, ``"callable"``, or a Constraint."""
    if spec is None:
        return _NoneConstraint()
    if spec is bool:
        return boolean
    if spec == "callable":
        return is_callable
    if isinstance(spec, Constraint):
        return spec
    raise TypeError(f"unknown constraint {spec!r}")


def validate_params(owner: str, params: Mapping, constraints: Mapping) -> None:
    """Raise ParameterError for the first parameter that meets none of its constraints."""
    for name, allowed in constraints.items():
        if name in params:
            check_argument(f"{owner}: {name}", params[name], *allowed)


def check_argument(name: str, value, *allowed) -> None:
    """Raise :class:`~discrepancy.errors.ParameterError` ("``name`` must be ...; got ...")
    unless ``value`` meets one of the constraints ``allowed`` (or their shorthands, see
    :func:`make_constraint`): the declared constraints of a function's own arguments."""
    rules = [make_constraint(c) for c in allowed]
    if not any(c.is_satisfied_by(value) for c in rules):
        expected = " or ".join(str(c) for c in rules)
        raise ParameterError(f"{name} must be {expected}; got {_shown(value)}")


def _shown(value) -> str:
    """A short, safe rendering of a rejected value (its repr when short, else its type)."""
    text = describe(value)
    if isinstance(value, (int, float, np.number, str, bool, type(None))):
        return repr(value)[:80]
    return text
