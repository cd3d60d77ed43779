"""Registries of named components (differentiation methods, optimizers), shared by the
Python API, the command line and model files.

A component is created from an instance, a registered name, or a *spec*: the text
``"savitzky_golay(window_length=31, polyorder=3)"`` (command line) or the mapping
``{"name": "savitzky_golay", "params": {"window_length": 31, "polyorder": 3}}`` (model
files). Spec text is parsed with :mod:`ast` and only literal values are accepted
(:func:`ast.literal_eval`), so nothing is ever evaluated. Unknown names raise an error
listing the valid ones; parameters are checked by the component's declared constraints.
"""
from __future__ import annotations

import ast
import math
from collections.abc import Mapping

from .errors import ParameterError, UnknownNameError, describe, short_repr

__all__ = ["Registry", "parse_spec"]

SCALARS = (bool, int, float, str, type(None))


class Registry:
    """Named classes of one kind.

    Args:
        kind: what the classes are, for messages (``"differentiation method"``).
        argument: the argument users pass them as (``"differentiation_method"``).
        base: the common base class; instances of it are accepted as they are.
    """

    def __init__(self, kind: str, argument: str, base: type):
        self.kind, self.argument, self.base = kind, argument, base
        self._classes: dict[str, type] = {}

    def register(self, name: str):
        """Class decorator adding a class under ``name`` (also stored as ``cls.spec_name``)."""
        def add(cls):
            self._classes[name] = cls
            cls.spec_name = name
            return cls
        return add

    def names(self) -> list[str]:
        """The registered names, sorted."""
        return sorted(self._classes)

    def get(self, name: str) -> type:
        """The class registered as ``name``; an unknown name raises
        :class:`~discrepancy.errors.UnknownNameError` listing the valid ones."""
        if name not in self._classes:
            raise UnknownNameError(f"{self.argument} {name!r} is not a known {self.kind}; "
                                   f"valid names: {', '.join(self.names())}")
        return self._classes[name]

    def create(self, spec, **params):
        """An instance from an instance (returned as is), a name or spec text (with
        ``params`` as keyword arguments), or a ``{"name", "params"}`` mapping; validated."""
        if isinstance(spec, self.base):
            return spec
        if isinstance(spec, Mapping):
            name, given = _from_mapping(spec, self.argument)
        elif isinstance(spec, str):
            name, given = parse_spec(spec, self.argument)
        else:
            raise UnknownNameError(f"{self.argument} must be a {self.kind} object or one of "
                                   f"{', '.join(self.names())}; got {describe(spec)}")
        cls = self.get(name)
        valid = cls._param_defaults()
        unknown = sorted((set(given) | set(params)) - set(valid))
        if unknown:
            raise ParameterError(f"{self.argument} {name!r}: {cls.__name__} has no parameter "
                                 f"{', '.join(map(repr, unknown))}; valid parameters: "
                                 f"{', '.join(valid) or 'none'}")
        try:
            obj = cls(**{**given, **params})
        except TypeError as e:
            raise ParameterError(f"{self.argument} {name!r}: {e}") from None
        obj._validate_params()
        return obj

    def to_spec(self, obj) -> dict:
        """``{"name", "params"}`` of a registered object whose parameters are JSON values
        (nested registered objects become nested specs)."""
        name = getattr(type(obj), "spec_name", None)
        if name is None or self._classes.get(name) is not type(obj):
            raise ParameterError(f"{type(obj).__name__} is not a registered {self.kind}, so it "
                                 "cannot be described by name")
        return {"name": name, "params": {k: _json_value(v, f"{name}.{k}")
                                         for k, v in obj.get_params(deep=False).items()}}


def _json_value(value, where):
    if isinstance(value, float) and not math.isfinite(value):
        raise ParameterError(f"{where} = {value} cannot be stored")
    if isinstance(value, SCALARS):
        return value
    if hasattr(value, "tolist"):
        return _json_value(value.tolist(), where)
    if isinstance(value, (list, tuple)):
        return [_json_value(v, where) for v in value]
    spec_name = getattr(type(value), "spec_name", None)
    if spec_name is not None:
        return {"name": spec_name, "params": {k: _json_value(v, f"{where}.{k}") for k, v in
                                              value.get_params(deep=False).items()}}
    raise ParameterError(f"{where} is a {type(value).__name__}, which a spec cannot hold")


def _from_mapping(spec: Mapping, argument: str) -> tuple[str, dict]:
    if set(spec) != {"name", "params"} or not isinstance(spec["name"], str) or \
            not isinstance(spec["params"], Mapping):
        raise ParameterError(f"{argument} spec must be {{'name': str, 'params': {{...}}}}; got "
                             f"keys {sorted(map(str, spec))}")
    return spec["name"], dict(spec["params"])


#: longest spec text accepted (a spec is a name and a few keyword arguments)
MAX_SPEC = 10_000


def parse_spec(text: str, argument: str = "spec") -> tuple[str, dict]:
    """``"name"`` or ``"name(key=value, ...)"`` -> ``(name, {key: value})``.

    Values must be Python literals (numbers, strings, True/False/None, lists/tuples of
    them); a bare identifier such as ``auto`` is read as the string ``"auto"``.
    """
    if len(text) > MAX_SPEC:
        raise ParameterError(f"{argument} spec {short_repr(text)} has {len(text)} characters; at "
                             f"most {MAX_SPEC}")
    try:
        tree = ast.parse(text.strip(), mode="eval").body
    except (SyntaxError, RecursionError, MemoryError, ValueError):
        raise ParameterError(f"{argument} {short_repr(text)} is not 'name' or "
                             "'name(key=value, ...)'") from None
    if isinstance(tree, ast.Name):
        return tree.id, {}
    if not (isinstance(tree, ast.Call) and isinstance(tree.func, ast.Name)) or tree.args:
        raise ParameterError(f"{argument} {short_repr(text)} must be 'name' or "
                             "'name(key=value, ...)' with keyword arguments only")
    params = {}
    for kw in tree.keywords:
        if kw.arg is None:
            raise ParameterError(f"{argument} {short_repr(text)}: '**' is not allowed")
        if isinstance(kw.value, ast.Name):
            params[kw.arg] = kw.value.id
            continue
        try:
            params[kw.arg] = ast.literal_eval(kw.value)
        except (ValueError, SyntaxError, TypeError, MemoryError, RecursionError):
            raise ParameterError(f"{argument} {short_repr(text)}: the value of {kw.arg} must be a "
                                 "literal (number, string, True/False/None)") from None
    return tree.func.id, params
