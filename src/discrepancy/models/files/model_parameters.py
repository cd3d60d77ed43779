"""The constructor parameters of a DiscrepancyModel in its model file (version 4 on).

:data:`CODECS` is the one list of how each constructor parameter is written and read back;
``tests/test_model_file_parameters.py`` checks that it names exactly the parameters of
``DiscrepancyModel.__init__`` and of its ``_parameter_constraints``, so a new parameter
cannot be forgotten by the file (as ``discrete_time`` and ``constraints`` once were).

A parameter is stored as given where JSON can hold it: numbers, names, spec text, a
registered component as its ``{"name", "params"}`` spec, :class:`Constraints` field by
field. A component JSON cannot hold (a user's own optimizer, a library object) is stored as
``{"as": "fitted"}``: the loaded model uses the fitted component the file stores elsewhere
(the library's terms, the fitted optimizer's spec), as files of version 3 did. Nothing read
is evaluated; every value is checked again by the model's declared constraints on load.
"""
from __future__ import annotations

import math

from ...errors import DiscrepancyError, ParameterError
from ..core.term_constraints import Constraints

#: the tags of a stored component parameter
COMPONENT_TAGS = ("none", "text", "spec", "fitted")


def _encode_component(registry_name):
    def encode(value):
        if value is None:
            return {"as": "none"}
        if isinstance(value, str):
            return {"as": "text", "value": value}
        registry = _registry(registry_name)
        if registry is not None:
            try:
                return {"as": "spec", "value": registry.to_spec(value)}
            except ParameterError:
                pass
        return {"as": "fitted"}
    return encode


def _decode_component(registry_name):
    def decode(data, fail):
        if not (isinstance(data, dict) and data.get("as") in COMPONENT_TAGS and
                set(data) == ({"as"} if data["as"] in ("none", "fitted") else {"as", "value"})):
            raise fail(f"must be {{'as': one of {list(COMPONENT_TAGS)}}} (with 'value' for "
                       "'text' and 'spec')")
        tag = data["as"]
        if tag == "none":
            return None
        if tag == "fitted":
            return FITTED
        if tag == "text":
            if not isinstance(data["value"], str) or len(data["value"]) > 10_000:
                raise fail("a 'text' value must be a spec string of at most 10000 characters")
            return data["value"]
        registry = _registry(registry_name)
        if registry is None:
            raise fail("has no registry of specs")
        try:
            return registry.create(data["value"])
        except DiscrepancyError as e:
            raise fail(str(e)) from None
    return decode


def _registry(name):
    if name == "optimizer":
        from ...optimizers.base import OPTIMIZERS
        return OPTIMIZERS
    if name == "differentiation_method":
        from ...differentiation.base import METHODS
        return METHODS
    return None


class _Fitted:
    """Marker: the parameter was not storable; use the fitted component from the file."""

    def __repr__(self) -> str:
        return "FITTED"


FITTED = _Fitted()


def _encode_names(value):
    return list(value) if isinstance(value, (list, tuple)) else value


def _decode_names(data, fail):
    if data is None or isinstance(data, str):
        return data
    if isinstance(data, list) and len(data) <= 100_000 and all(isinstance(n, str) for n in data):
        return data
    raise fail("must be null, a name or a list of names")


def _encode_linear(rows):
    return [[[[str(s), str(t), float(a)] for (s, t), a in weights.items()], float(bound)]
            for weights, bound in rows]


def _decode_linear(data, fail, field):
    def number(v):
        return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)

    ok = isinstance(data, list) and all(
        isinstance(row, list) and len(row) == 2 and number(row[1]) and isinstance(row[0], list)
        and all(isinstance(w, list) and len(w) == 3 and isinstance(w[0], str)
                and isinstance(w[1], str) and number(w[2]) for w in row[0]) for row in data)
    if not ok:
        raise fail(f"{field} must be a list of [[[state, term, coefficient], ...], bound]")
    return [({(s, t): float(a) for s, t, a in weights}, float(bound)) for weights, bound in data]


_LINEAR = ("equal", "at_most", "at_least")


def _encode_constraints(value):
    if value is None:
        return None
    return {"exact_equations": list(value.exact_equations),
            "only": None if value.only is None else {k: list(v) for k, v in value.only.items()},
            **{field: _encode_linear(getattr(value, field)) for field in _LINEAR}}


def _decode_constraints(data, fail):
    if data is None:
        return None
    keys = {"exact_equations", "only", *_LINEAR}
    if not isinstance(data, dict) or set(data) != keys:
        raise fail(f"must be null or an object with exactly the keys {sorted(keys)}")
    fields = {field: _decode_linear(data[field], fail, field) for field in _LINEAR}
    try:
        return Constraints(exact_equations=data["exact_equations"], only=data["only"], **fields)
    except DiscrepancyError as e:
        raise fail(str(e)) from None


def _plain(kind):
    def decode(data, fail):
        if type(data) is not kind:
            raise fail(f"must be a {kind.__name__}")
        return data
    return decode


def _same(value):
    return value


#: parameter -> (encode(value) -> JSON, decode(JSON, fail) -> value); ``prior`` is stored in
#: the file's own ``prior`` record (code is never stored), so it has no entry here
CODECS = {
    "feature_library": (_encode_component(None), _decode_component(None)),
    "optimizer": (_encode_component("optimizer"), _decode_component("optimizer")),
    "differentiation_method": (_encode_component("differentiation_method"),
                               _decode_component("differentiation_method")),
    "state_names": (_encode_names, _decode_names),
    "input_names": (_encode_names, _decode_names),
    "constraints": (_encode_constraints, _decode_constraints),
    "discrete_time": (bool, _plain(bool)),
    "selection": (_same, _plain(str)),
}
#: parameters stored outside the ``parameters`` record
STORED_ELSEWHERE = ("prior",)


def encode_parameters(model) -> dict:
    """The ``parameters`` record of ``model``'s constructor arguments."""
    params = model.get_params(deep=False)
    return {name: encode(params[name]) for name, (encode, _) in CODECS.items()}


def decode_parameters(data, fail) -> dict:
    """The constructor arguments of a ``parameters`` record (``FITTED`` where the file says
    the fitted component stands in); ``fail(why)`` makes the ModelFileError."""
    if not isinstance(data, dict) or set(data) != set(CODECS):
        raise fail(f"parameters must be an object with exactly the keys {sorted(CODECS)}")
    return {name: decode(data[name], lambda why, n=name: fail(f"parameters.{n} {why}"))
            for name, (_, decode) in CODECS.items()}


def check_parameters(cls, given: dict, fail) -> None:
    """Check the constructor parameters a file stores as given (version 4 on) with the
    class's declared constraints before anything is built from them; a value they refuse,
    or a spec that does not parse, raises ``fail(why)`` (a ModelFileError: the file was
    edited)."""
    from ...differentiation.base import METHODS
    from ...libraries.spec import parse_library
    from ...optimizers.base import OPTIMIZERS
    from ...symbolic import IDENTIFIER

    model = cls(**{k: v for k, v in given.items() if v is not FITTED})
    try:
        model._validate_params()
        if isinstance(model.feature_library, str):
            parse_library(model.feature_library)
        for registry in (OPTIMIZERS, METHODS):
            if isinstance(given.get(registry.argument), str):
                registry.create(given[registry.argument])
        for key in ("state_names", "input_names"):
            names = [given[key]] if isinstance(given.get(key), str) else given.get(key) or []
            bad = [n for n in names if not IDENTIFIER.match(n)]
            if bad:
                raise ParameterError(f"{key} must be identifiers; got {bad[:3]}")
    except DiscrepancyError as e:
        raise fail(f"parameters: {e}") from None
