"""Model files: versioned JSON with terms stored as structured expressions.

Nothing read from a file is evaluated as code: expressions are rebuilt node by
node from a whitelist (:func:`discrepancy.symbolic.from_data`), names must be
identifiers, numbers must be finite, and every shape is checked.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from .. import __version__
from ..errors import ModelFileError, ParameterError
from ..symbolic import IDENTIFIER, from_data, to_data

FORMAT = "discrepancy-model"
VERSION = 1
KEYS = {"format", "version", "written_by", "state_names", "input_names", "features",
        "coefficients", "prior", "user_functions", "metadata"}


def save_model(model, path) -> None:
    model.check_is_fitted()
    if model.prior is None:
        prior = None
    elif model.prior_.is_symbolic:
        prior = {"kind": "sympy", "expressions": [to_data(e) for e in model.prior_.expressions]}
    else:
        prior = {"kind": "callable", "name": getattr(model.prior, "__qualname__", "prior")}
    doc = {
        "format": FORMAT, "version": VERSION, "written_by": f"discrepancy {__version__}",
        "state_names": model.state_names_, "input_names": model.input_names_,
        "features": [to_data(e) for e in model.feature_expressions_],
        "coefficients": model.coef_.tolist(), "prior": prior,
        "user_functions": sorted(model.user_functions_),
        "metadata": {"optimizer": repr(model.optimizer_) if hasattr(model, "optimizer_") else "",
                     "feature_library": repr(model.feature_library),
                     "differentiation_method": repr(model.differentiation_method_),
                     "n_samples": int(getattr(getattr(model, "statistics_", None), "count", 0))},
    }
    Path(path).write_text(json.dumps(doc, indent=1))


def _fail(why: str) -> ModelFileError:
    return ModelFileError(f"model file: {why}; it is corrupted, was edited, or is not a "
                          f"{FORMAT} file")


def _names(doc, key) -> list[str]:
    names = doc[key]
    if not isinstance(names, list) or not all(isinstance(n, str) and IDENTIFIER.match(n)
                                              for n in names):
        raise _fail(f"{key} must be a list of identifiers")
    return names


def _coefficients(doc, n: int, p: int) -> np.ndarray:
    rows = doc["coefficients"]
    ok = isinstance(rows, list) and len(rows) == n and all(
        isinstance(r, list) and len(r) == p and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
            for v in r) for r in rows)
    if not ok:
        raise _fail(f"coefficients must be {n} rows of {p} finite numbers")
    return np.array(rows, dtype=float).reshape(n, p)


def read_model_file(path) -> dict:
    """Parse and validate a model file; returns its fields with expressions rebuilt."""
    try:
        text = Path(path).read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise _fail("not UTF-8 text") from None
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as e:
        raise _fail(f"not valid JSON ({e.msg} at line {e.lineno})") from None
    except (ValueError, RecursionError) as e:  # huge integer literals, absurd nesting
        raise _fail(f"not a usable JSON document ({type(e).__name__})") from None
    if not isinstance(doc, dict) or set(doc) != KEYS:
        got = sorted(doc) if isinstance(doc, dict) else type(doc).__name__
        raise _fail(f"expected the keys {sorted(KEYS)}, got {got}")
    if doc["format"] != FORMAT or type(doc["version"]) is not int or doc["version"] != VERSION:
        raise _fail(f"format {doc['format']!r:.40} version {doc['version']!r:.20} is not "
                    f"{FORMAT!r} version {VERSION}")
    states, inputs = _names(doc, "state_names"), _names(doc, "input_names")
    functions = doc["user_functions"]
    if not isinstance(functions, list) or not all(isinstance(f, str) and IDENTIFIER.match(f)
                                                  for f in functions):
        raise _fail("user_functions must be a list of identifiers")
    if not isinstance(doc["features"], list) or not doc["features"]:
        raise _fail("features must be a non-empty list of expressions")
    allowed = set(states) | set(inputs)
    features = [_expression(f, f"features[{i}]", allowed, functions)
                for i, f in enumerate(doc["features"])]
    coef = _coefficients(doc, len(states), len(features))
    return {"state_names": states, "input_names": inputs, "features": features,
            "coefficients": coef, "prior": _prior(doc["prior"], states, allowed),
            "user_functions": functions}


def _expression(data, where, allowed, functions):
    expr = from_data(data, where=where, functions=functions)
    if not {s.name for s in expr.free_symbols} <= allowed:
        raise _fail(f"{where} uses variables outside {sorted(allowed)}")
    return expr


def _prior(prior, states, allowed):
    if prior is None:
        return None
    if not isinstance(prior, dict) or prior.get("kind") not in ("sympy", "callable"):
        raise _fail("prior must be null or an object with kind 'sympy' or 'callable'")
    expected = {"kind", "expressions"} if prior["kind"] == "sympy" else {"kind", "name"}
    if set(prior) != expected:
        raise _fail(f"a {prior['kind']} prior must have exactly the keys {sorted(expected)}")
    if prior["kind"] == "callable":
        if not isinstance(prior["name"], str) or len(prior["name"]) > 200:
            raise _fail("a callable prior's name must be a short string")
        return prior
    exprs = prior["expressions"]
    if not isinstance(exprs, list) or len(exprs) != len(states):
        raise _fail(f"prior expressions must be a list of {len(states)} expressions")
    return {"kind": "sympy",
            "expressions": [_expression(e, f"prior[{i}]", allowed, [])
                            for i, e in enumerate(exprs)]}


def load_model(path, prior=None, *, functions=None):
    """Load a model saved with :meth:`DiscrepancyModel.save`.

    Args:
        path: the JSON file.
        prior: the callable prior the model was fitted with (needed when the file says its
            prior was a Python callable; a sympy prior is stored in the file itself).
        functions: numpy functions of custom terms, by the names the file lists.
    """
    from .discrepancy_model import DiscrepancyModel

    fields = read_model_file(path)
    stored = fields["prior"]
    if prior is None and stored is not None:
        if stored["kind"] == "callable":
            raise ParameterError("this model was fitted with a Python callable prior, which "
                                 "files never store as code; pass it: load_model(path, "
                                 "prior=f_m)")
        prior = stored["expressions"]
    missing = sorted(set(fields["user_functions"]) - set(functions or {}))
    if missing:
        raise ParameterError(f"the model uses numpy functions {missing}; pass them as "
                             "load_model(path, functions={name: callable})")
    model = DiscrepancyModel(prior=prior, state_names=fields["state_names"],
                             input_names=fields["input_names"])
    model._setup(len(fields["state_names"]), len(fields["input_names"]))
    model.feature_library_ = None
    used = {n: functions[n] for n in fields["user_functions"]}
    model._set_coefficients(fields["coefficients"], fields["features"], used)
    return model


