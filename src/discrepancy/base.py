"""The one base of every public estimator-like class (models, libraries, optimizers,
differentiators): scikit-learn's contract, written small.

* ``__init__`` stores its keyword arguments unchanged and validates nothing;
* :meth:`Estimator.get_params` / :meth:`Estimator.set_params` see exactly the constructor's
  arguments (nested ones as ``library__degree``), so ``sklearn.base.clone`` and grid searches work;
* ``repr`` shows the arguments that differ from their defaults;
* ``_validate_params()`` checks them against the class's ``_parameter_constraints``
  (see :mod:`discrepancy.constraints`) when they are used (``fit``, a call);
* :meth:`Estimator.check_is_fitted` raises one :class:`~discrepancy.errors.NotFittedError`.
"""
from __future__ import annotations

import inspect
from typing import ClassVar

import numpy as np

from .constraints import validate_params
from .errors import NotFittedError, ParameterError

__all__ = ["Estimator", "clone"]

_NO_DEFAULT = inspect.Parameter.empty


class Estimator:
    """Base class: parameters are the ``__init__`` arguments, fitted state ends in ``_``."""

    #: argument name -> list of acceptable constraints (any one suffices)
    _parameter_constraints: ClassVar[dict] = {}
    #: what to call before methods that need a fit, for the NotFittedError message
    _fit_hint: ClassVar[str] = "fit"
    #: the attribute that marks a fit (None: any attribute ending in ``_``)
    _fitted_attribute: ClassVar[str | None] = None

    @classmethod
    def _param_defaults(cls) -> dict:
        """``{name: default}`` of the constructor's arguments (``empty`` when required)."""
        init = cls.__init__
        if init is object.__init__:
            return {}
        params = inspect.signature(init).parameters.values()
        out = {}
        for p in params:
            if p.name == "self" or p.kind in (p.VAR_KEYWORD,):
                continue
            if p.kind is p.VAR_POSITIONAL:
                raise TypeError(f"{cls.__name__}.__init__ must not take *args (estimator "
                                "contract: every parameter has a name)")
            out[p.name] = p.default
        return out

    def get_params(self, deep: bool = True) -> dict:
        """The constructor's arguments as given; with ``deep``, also those of nested
        estimators as ``name__param``."""
        out = {}
        for name in self._param_defaults():
            value = getattr(self, name)
            out[name] = value
            if deep and isinstance(value, Estimator):
                out.update({f"{name}__{k}": v for k, v in value.get_params(deep=True).items()})
        return out

    def set_params(self, **params) -> Estimator:
        """Set constructor arguments (``name=value``, or ``name__param=value`` for nested
        estimators); returns self. Unknown names raise ParameterError."""
        valid = self._param_defaults()
        nested: dict[str, dict] = {}
        for key, value in params.items():
            name, _, sub = key.partition("__")
            if name not in valid:
                raise ParameterError(f"{type(self).__name__} has no parameter {name!r}; valid "
                                     f"parameters: {', '.join(valid)}")
            if sub:
                nested.setdefault(name, {})[sub] = value
            else:
                setattr(self, name, value)
        for name, sub_params in nested.items():
            inner = getattr(self, name)
            if not isinstance(inner, Estimator):
                raise ParameterError(f"{type(self).__name__}.{name} is "
                                     f"{type(inner).__name__}, which has no parameters to set "
                                     f"({', '.join(sub_params)})")
            inner.set_params(**sub_params)
        return self

    def _validate_params(self) -> None:
        """Check every argument against ``_parameter_constraints``, then ``_check_params``."""
        validate_params(type(self).__name__, self.get_params(deep=False),
                        self._parameter_constraints)
        self._check_params()

    def _check_params(self) -> None:
        """Hook: checks that tie several arguments together (after the declared ones)."""

    def check_is_fitted(self) -> None:
        """Raise NotFittedError unless the object holds fitted state (``_fitted_attribute``,
        or any attribute ending in ``_``)."""
        if self._fitted_attribute is not None:
            fitted = hasattr(self, self._fitted_attribute)
        else:
            fitted = any(k.endswith("_") and not k.startswith("__") for k in vars(self))
        if not fitted:
            raise NotFittedError(f"this {type(self).__name__} is not fitted yet; call "
                                 f"{self._fit_hint} first")

    def __sklearn_is_fitted__(self) -> bool:
        """Whether the object is fitted (scikit-learn's ``check_is_fitted`` asks this)."""
        try:
            self.check_is_fitted()
        except NotFittedError:
            return False
        return True

    def __sklearn_tags__(self):
        """scikit-learn's estimator tags (its grid searches ask for them); scikit-learn is
        imported only when they are asked for."""
        from sklearn.base import BaseEstimator

        return BaseEstimator.__sklearn_tags__(self)

    def __repr__(self) -> str:
        shown = []
        for name, default in self._param_defaults().items():
            value = getattr(self, name, None)
            if default is _NO_DEFAULT or not _same(value, default):
                shown.append(f"{name}={_short_repr(value)}")
        return f"{type(self).__name__}({', '.join(shown)})"


def clone(estimator: Estimator) -> Estimator:
    """An unfitted copy of ``estimator`` with the same constructor arguments (the values
    themselves shared, not copied: nested estimators are not fitted in place by their
    owners). The library's one clone, for candidates fitted side by side from a template."""
    return type(estimator)(**estimator.get_params(deep=False))


def _same(value, default) -> bool:
    if value is default:
        return True
    if isinstance(value, np.ndarray) or isinstance(default, np.ndarray):
        return False
    try:
        return type(value) is type(default) and bool(value == default)
    except Exception:  # objects whose comparison is not a truth value
        return False


def _short_repr(value) -> str:
    if callable(value) and not isinstance(value, Estimator) and hasattr(value, "__qualname__"):
        return f"<function {value.__qualname__}>"
    text = repr(value)
    return text if len(text) <= 200 else text[:197] + "..."
