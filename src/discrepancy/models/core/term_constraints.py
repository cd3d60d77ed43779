"""Constraints on a discrepancy model's coefficients, written with the model's own names.

A discrepancy modeller knows things the data should not have to teach: "the kinematic
equations ``(phi)' = dphi`` are exact", "the input enters only the cart's equation", "this
friction coefficient is not negative". :class:`Constraints` says them with state and term
names; the model turns them into index form
(:class:`~discrepancy.optimizers.linear_constraints.LinearConstraints`) once the library's
terms are known, and the optimizer honours them on the Gram statistics, so streamed and Dask
fits keep them too.
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from ...errors import ParameterError, UnknownNameError, describe
from ...optimizers.linear_constraints import LinearConstraints

Linear = tuple[Mapping[tuple[str, str], float], float]


@dataclass(frozen=True)
class Constraints:
    """Term masks and linear constraints by name.

    Args:
        exact_equations: states whose equations get no correction (e.g. ``["x1"]`` for
            ``x1' = x2``).
        only: ``{term: [states]}``: the term may appear only in these equations.
        equal: ``[({(state, term): a, ...}, b), ...]``: ``Σ a ξ[state, term] = b``.
        at_most: the same form for ``Σ a ξ <= b``; at_least: for ``Σ a ξ >= b``.

    Terms are named as the model prints them (``model.get_feature_names()``).
    """

    exact_equations: Sequence[str] = ()
    only: Mapping[str, Sequence[str]] | None = None
    equal: Sequence[Linear] = ()
    at_most: Sequence[Linear] = ()
    at_least: Sequence[Linear] = ()

    def __post_init__(self):
        lists = [("exact_equations", self.exact_equations)]
        if self.only is not None:
            if not isinstance(self.only, Mapping) or not all(isinstance(k, str)
                                                              for k in self.only):
                raise ParameterError(f"Constraints.only must be None or a mapping of term names "
                                     f"to lists of states; got {describe(self.only)}")
            lists += [(f"only[{k!r}]", v) for k, v in self.only.items()]
        for name, value in lists:
            if isinstance(value, str):
                raise ParameterError(f"Constraints.{name} must be a list of state names; got "
                                     f"the string {value!r} (write [{value!r}])")
            if not isinstance(value, (list, tuple)) or not all(isinstance(v, str) for v in value):
                raise ParameterError(f"Constraints.{name} must be a list of state names; got "
                                     f"{describe(value)}")
        for name in ("equal", "at_most", "at_least"):
            if not isinstance(getattr(self, name), (list, tuple)):
                raise ParameterError(f"Constraints.{name} must be a list of ({{(state, term): "
                                     f"coefficient}}, bound) pairs; got "
                                     f"{describe(getattr(self, name))}")
        # lists and tuples alike, so equal constraints compare equal (e.g. after a file)
        for name in ("exact_equations", "equal", "at_most", "at_least"):
            object.__setattr__(self, name, tuple(getattr(self, name)))
        if self.only is not None:
            object.__setattr__(self, "only", {k: tuple(v) for k, v in self.only.items()})

    def compile(self, state_names: Sequence[str], terms: Sequence[str]) -> LinearConstraints:
        """Index form for equations ``state_names`` and library ``terms``."""
        states, terms = list(state_names), list(terms)
        mask = np.ones((len(states), len(terms)), bool)
        for state in self.exact_equations:
            mask[_index(state, states, "state (exact_equations)")] = False
        for term, allowed in (self.only or {}).items():
            j = _index(term, terms, "term (only)")
            rows = [_index(s, states, f"state (only[{term!r}])") for s in allowed]
            mask[[i for i in range(len(states)) if i not in rows], j] = False
        eq = _rows(self.equal, states, terms, "equal", 1.0)
        ub = _rows(self.at_most, states, terms, "at_most", 1.0) + \
            _rows(self.at_least, states, terms, "at_least", -1.0)
        for lhs, _ in eq + ub:
            outside = (lhs.reshape(mask.shape) != 0) & ~mask
            if outside.any():
                i, j = np.argwhere(outside)[0]
                raise ParameterError(f"a linear constraint uses ({states[i]!r}, {terms[j]!r}), "
                                     "which the masks exclude")
        return LinearConstraints(len(states), len(terms), mask, *_stack(eq), *_stack(ub))


def _index(name, names, what) -> int:
    if name not in names:
        raise UnknownNameError(f"Constraints: {what} {name!r} is not one of {names}")
    return names.index(name)


def _rows(specs, states, terms, what, sign) -> list[tuple[np.ndarray, float]]:
    out = []
    for k, spec in enumerate(specs):
        if not (isinstance(spec, (tuple, list)) and len(spec) == 2 and
                isinstance(spec[0], Mapping)):
            raise ParameterError(f"Constraints.{what}[{k}] must be ({{(state, term): "
                                 f"coefficient, ...}}, bound); got {spec!r:.80}")
        weights, bound = spec
        lhs = np.zeros(len(states) * len(terms))
        for key, a in weights.items():
            if not (isinstance(key, tuple) and len(key) == 2):
                raise ParameterError(f"Constraints.{what}[{k}]: keys must be (state, term) "
                                     f"pairs; got {key!r}")
            i = _index(key[0], states, f"state in {what}[{k}]")
            j = _index(key[1], terms, f"term in {what}[{k}]")
            lhs[i * len(terms) + j] = sign * _finite(a, what, k)
        out.append((lhs, sign * _finite(bound, what, k)))
    return out


def _finite(value, what, k) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        v = np.nan
    if not np.isfinite(v) or isinstance(value, bool):
        raise ParameterError(f"Constraints.{what}[{k}]: coefficients and bounds must be "
                             f"finite numbers; got {value!r}")
    return v


def _stack(rows):
    if not rows:
        return None, None
    return np.array([r for r, _ in rows]), np.array([b for _, b in rows])
