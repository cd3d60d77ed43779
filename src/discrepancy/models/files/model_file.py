"""Model files: versioned JSON with terms stored as structured expressions.

:func:`encode` turns a fitted model into a JSON-compatible dict (``DiscrepancyModel.to_state``)
and :func:`decode` checks such a dict field by field and rebuilds what
``DiscrepancyModel.from_state`` needs. Nothing read from a file is evaluated as code:
expressions are rebuilt node by node from a whitelist (:func:`discrepancy.symbolic.from_data`),
components (optimizer, differentiation method) through their registries with declared
parameter constraints, names must be identifiers, numbers finite, every shape is checked.
Writes are atomic (temporary file in the same folder, fsync, rename).
"""
from __future__ import annotations

import json
import math
import os
import tempfile
from pathlib import Path

import numpy as np
import sympy as sp

from ..._version import __version__
from ...data.containers import as_path
from ...differentiation.base import METHODS
from ...errors import DiscrepancyError, MissingFileError, ModelFileError, ParameterError
from ...libraries import CustomLibrary
from ...optimizers.base import OPTIMIZERS
from ...resources import check_features
from ...symbolic import IDENTIFIER, from_data, to_data
from ..simulate.region import FittedRegion
from .model_parameters import decode_parameters, encode_parameters

_NON_REAL = (sp.zoo, sp.oo, -sp.oo, sp.nan, sp.I)
FORMAT = "discrepancy-model"
VERSION = 4
#: keys of each version (version 1 files, written before components were stored, version 2
#: files, before the fitted region and the forecast choice were, and version 3 files, before
#: every constructor parameter was (:mod:`discrepancy.models.files.model_parameters`), still load)
KEYS = {1: {"format", "version", "written_by", "state_names", "input_names", "features",
            "coefficients", "prior", "user_functions", "metadata"}}
KEYS[2] = KEYS[1] | {"optimizer", "differentiation_method", "fit"}
KEYS[3] = KEYS[2] | {"region"}
KEYS[4] = KEYS[3] | {"parameters"}
#: keys of the ``fit`` record by version
FIT_KEYS = {2: {"n_samples", "differentiation_choice"}}
FIT_KEYS[3] = FIT_KEYS[2] | {"selection"}
FIT_KEYS[4] = FIT_KEYS[3]
#: larger files are refused before parsing (a model of 1000 terms x 100 states is ~2 MB)
MAX_BYTES = 20 * 2**20


# ------------------------------------------------------------------------ writing
def encode(model) -> dict:
    """The model file's content for a fitted model."""

    if model.prior is None:
        prior = None
    elif model.prior_.is_symbolic:
        prior = {"kind": "sympy", "expressions": [to_data(e) for e in model.prior_.expressions]}
    else:
        prior = {"kind": "callable", "name": getattr(model.prior, "__qualname__", "prior")[:200]}
    stats = model.statistics_
    region = getattr(model, "region_", None)
    chosen = getattr(model, "forecast_selection_", None)
    return {
        "format": FORMAT, "version": VERSION, "written_by": f"discrepancy {__version__}",
        "state_names": model.state_names_, "input_names": model.input_names_,
        "features": [to_data(e) for e in model.feature_expressions_],
        "coefficients": model.coef_.tolist(), "prior": prior,
        "user_functions": sorted(model.feature_library_.user_functions()),
        "optimizer": _spec_or_none(OPTIMIZERS, model.optimizer_),
        "differentiation_method": _spec_or_none(METHODS, model.differentiation_method_),
        "fit": {"n_samples": None if stats is None else int(stats.count),
                "differentiation_choice": _plain(model.differentiation_choice_),
                "selection": None if chosen is None else _plain(chosen.summary())},
        "region": None if region is None else region.to_data(),
        "parameters": encode_parameters(model),
        "metadata": {"optimizer": repr(model.optimizer_),
                     "feature_library": repr(model.feature_library),
                     "differentiation_method": repr(model.differentiation_method_)},
    }


def _spec_or_none(registry, obj):
    try:
        return registry.to_spec(obj)
    except ParameterError:  # a user's own component: described in metadata only
        return None


def write_json(path, doc: dict) -> None:
    """Write ``doc`` to ``path`` atomically: a failed or killed write leaves any existing
    file as it was. Raises ModelFileError naming the path on OS errors."""
    path = as_path(path, "path")
    if path.is_dir():
        raise ModelFileError(f"path {str(path)!r} is a folder; give a file name such as "
                             f"{str(path / 'model.json')!r}")
    text = json.dumps(doc, indent=1, allow_nan=False)
    folder = path.parent if str(path.parent) else Path(".")
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=folder)
    except OSError as e:
        raise ModelFileError(f"cannot write {str(path)!r}: {e.strerror or e}") from None
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except OSError as e:
        Path(tmp).unlink(missing_ok=True)
        raise ModelFileError(f"cannot write {str(path)!r}: {e.strerror or e}; any existing "
                             "file there is unchanged") from None
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


# ------------------------------------------------------------------------ reading
def corrupted(why: str) -> ModelFileError:
    """The error for a model file that cannot be read, saying ``why``."""
    return ModelFileError(f"model file: {why}; it is corrupted, was edited, or is not a "
                          f"{FORMAT} file")


def read_json(path) -> dict:
    """Parse a model file (size-limited) into a dict; :func:`decode` checks its fields."""
    path = as_path(path, "model file")
    if path.is_dir():
        raise ModelFileError(f"model file {str(path)!r} is a folder, not a file")
    if not path.is_file():
        raise MissingFileError(f"model file {str(path)!r} does not exist")
    if path.stat().st_size > MAX_BYTES:
        raise corrupted(f"{path.stat().st_size} bytes is more than the {MAX_BYTES} a model file "
                    "may have")
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise corrupted("not UTF-8 text") from None
    except OSError as e:
        raise ModelFileError(f"cannot read model file {str(path)!r}: {e.strerror or e}") from None
    try:
        return json.loads(text)
    except json.JSONDecodeError as e:
        raise corrupted(f"not valid JSON ({e.msg} at line {e.lineno})") from None
    except (ValueError, RecursionError) as e:  # huge integer literals, absurd nesting
        raise corrupted(f"not a usable JSON document ({type(e).__name__})") from None


def decode(doc, *, prior=None, functions=None) -> dict:
    """Check a model file's content and return the fields ``from_state`` needs: names,
    coefficients ``(n, p)``, the library of stored terms, optimizer and differentiation
    method, the prior (the given callable, or the stored sympy expressions) and, from
    version 4, the constructor's ``parameters`` as given (see :mod:`.model_parameters`)."""

    version = _version(doc)
    choice = _fit_record(doc["fit"], version) if version >= 2 else None
    states, inputs = _names(doc, "state_names"), _names(doc, "input_names")
    declared = doc["user_functions"]
    if not isinstance(declared, list) or not all(isinstance(f, str) and IDENTIFIER.match(f)
                                                 for f in declared):
        raise corrupted("user_functions must be a list of identifiers")
    if not isinstance(doc["features"], list) or not doc["features"]:
        raise corrupted("features must be a non-empty list of expressions")
    check_features("the model file's library", len(doc["features"]))
    allowed = set(states) | set(inputs)
    features = [_expression(f, f"features[{i}]", allowed, declared)
                for i, f in enumerate(doc["features"])]
    coef = _coefficients(doc, len(states), len(features))
    missing = sorted(set(declared) - set(functions or {}))
    if missing:
        raise ParameterError(f"the model uses numpy functions {missing}; pass them as "
                             "load_model(path, functions={name: callable})")
    used = {n: functions[n] for n in declared}
    return {"state_names": states, "input_names": inputs, "coefficients": coef,
            "prior": _prior(doc["prior"], states, allowed, prior),
            "library": CustomLibrary(features, functions=used or None),
            "optimizer": _component(doc, "optimizer", version),
            "differentiation_method": _component(doc, "differentiation_method", version),
            "differentiation_choice": choice,
            "region": _region(doc, version, [*states, *inputs]),
            "parameters": decode_parameters(doc["parameters"], corrupted) if version >= 4 else {}}


def _fit_record(fit, version: int) -> dict | None:
    """The checked ``fit`` record; returns the stored differentiation choice (or None)."""
    keys = FIT_KEYS[version]
    if not (isinstance(fit, dict) and set(fit) == keys
            and (fit["n_samples"] is None or type(fit["n_samples"]) is int)):
        raise corrupted(f"fit must be an object with exactly the keys {sorted(keys)} "
                    "('n_samples': an integer or null, the others objects or null)")
    for key in keys - {"n_samples"}:
        value = fit[key]
        if value is not None and not (isinstance(value, dict) and _is_plain(value, 0)):
            raise corrupted(f"fit.{key} must be an object of names, numbers and lists")
    return fit["differentiation_choice"]


def _region(doc, version: int, names):
    """The fitted region (None before version 3 or when none was recorded)."""

    if version < 3 or doc["region"] is None:
        return None
    try:
        return FittedRegion.from_data(doc["region"], names)
    except ValueError as e:
        raise corrupted(str(e)) from None


def _is_plain(value, depth: int) -> bool:
    """JSON of bounded depth whose numbers are finite (what a choice record may hold)."""
    if depth > 4:
        return False
    if isinstance(value, dict):
        return len(value) <= 1000 and all(isinstance(k, str) and len(k) <= 100 and
                                          _is_plain(v, depth + 1) for k, v in value.items())
    if isinstance(value, list):
        return len(value) <= 1000 and all(_is_plain(v, depth + 1) for v in value)
    if isinstance(value, float):
        return math.isfinite(value)
    return isinstance(value, (str, int, bool, type(None))) and \
        (not isinstance(value, str) or len(value) <= 1000)


def _plain(value):
    """``value`` with numpy numbers as Python numbers (for the JSON file)."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


def _version(doc) -> int:
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        got = type(doc).__name__ if not isinstance(doc, dict) else repr(doc.get("format"))[:40]
        raise corrupted(f"format is {got}, not {FORMAT!r}")
    version = doc.get("version")
    if type(version) is not int or version not in KEYS:
        raise corrupted(f"version {version!r:.20} is not one of {sorted(KEYS)} (a newer "
                    "discrepancy may have written it)")
    if set(doc) != KEYS[version]:
        raise corrupted(f"version {version} needs exactly the keys {sorted(KEYS[version])}; got "
                    f"{sorted(map(str, doc))[:20]}")
    return version


def _names(doc, key) -> list[str]:
    names = doc[key]
    if not isinstance(names, list) or not all(isinstance(n, str) and IDENTIFIER.match(n)
                                              for n in names) or len(set(names)) != len(names):
        raise corrupted(f"{key} must be a list of distinct identifiers")
    return names


def _coefficients(doc, n: int, p: int) -> np.ndarray:
    rows = doc["coefficients"]
    ok = isinstance(rows, list) and len(rows) == n and all(
        isinstance(r, list) and len(r) == p and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
            for v in r) for r in rows)
    if not ok:
        raise corrupted(f"coefficients must be {n} rows of {p} finite numbers")
    return np.array(rows, dtype=float).reshape(n, p)


def _expression(data, where, allowed, functions):
    expr = from_data(data, where=where, functions=functions)
    if not {s.name for s in expr.free_symbols} <= allowed:
        raise corrupted(f"{where} uses variables outside {sorted(allowed)}")
    if expr.is_number and (expr.has(*_NON_REAL) or not _finite_number(expr)):
        raise corrupted(f"{where} is the constant {str(expr)[:40]}, which is not a finite real "
                    "number")
    return expr


def _finite_number(expr) -> bool:
    try:
        return math.isfinite(complex(expr).real) and complex(expr).imag == 0
    except (TypeError, ValueError, OverflowError):
        return False


def _prior(stored, states, allowed, given):
    if stored is not None and (not isinstance(stored, dict) or
                               stored.get("kind") not in ("sympy", "callable")):
        raise corrupted("prior must be null or an object with kind 'sympy' or 'callable'")
    if stored is not None:
        expected = {"kind", "expressions"} if stored["kind"] == "sympy" else {"kind", "name"}
        if set(stored) != expected:
            raise corrupted(f"a {stored['kind']} prior must have exactly the keys "
                            f"{sorted(expected)}")
    if given is not None:
        if stored is None:
            raise ParameterError("this model was fitted without a prior (plain SINDy); do not "
                                 "pass one to load_model")
        return given
    if stored is None:
        return None
    if stored["kind"] == "callable":
        raise ParameterError("this model was fitted with a Python callable prior, which files "
                             "never store as code; pass it: load_model(path, prior=f_m)")
    exprs = stored["expressions"]
    if not isinstance(exprs, list) or len(exprs) != len(states):
        raise corrupted(f"prior expressions must be a list of {len(states)} expressions")
    return [_expression(e, f"prior[{i}]", allowed, []) for i, e in enumerate(exprs)]


def _component(doc, key, version):
    """A stored optimizer / differentiation method rebuilt through its registry."""

    if version < 2 or doc[key] is None:
        return None
    registry = OPTIMIZERS if key == "optimizer" else METHODS
    try:
        return registry.create(doc[key])
    except DiscrepancyError as e:
        raise corrupted(f"{key}: {e}") from None


