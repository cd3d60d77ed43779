"""Fourier library: sin and cos of integer (or given) multiples of each variable."""
from __future__ import annotations

import numpy as np
import sympy as sp

from ..constraints import Integral, Interval, Predicate
from ..errors import ParameterError
from .base import VARIABLES, BaseLibrary


class FourierLibrary(BaseLibrary):
    """``sin(k z_j)``, ``cos(k z_j)`` for frequencies ``k`` and chosen variables ``z_j``.

    Order as PySINDy: for each frequency, for each variable, sin then cos.

    Args:
        n_frequencies: use ``k = 1, ..., n_frequencies`` (ignored if ``frequencies`` given).
        frequencies: explicit list of frequencies (rad per unit of the variable).
        include_sin, include_cos: which of the two to include.
        variables: names or indices of z = [x, u] to use; ``None`` = all.
    """

    _parameter_constraints = {
        "n_frequencies": [Interval(Integral, 1, None)],
        "frequencies": [None, Predicate(lambda v: isinstance(v, (list, tuple)) and len(v) > 0
                                        and all(np.isfinite(float(f)) and float(f) != 0
                                                for f in v),
                                        "a non-empty list of finite, non-zero numbers")],
        "include_sin": [bool], "include_cos": [bool], "variables": VARIABLES}

    def __init__(self, n_frequencies: int = 1, *, frequencies=None, include_sin: bool = True,
                 include_cos: bool = True, variables=None):
        super().__init__(variables=variables)
        self.n_frequencies = n_frequencies
        self.frequencies = frequencies
        self.include_sin = include_sin
        self.include_cos = include_cos

    def _freqs(self) -> list:
        if self.frequencies is not None:
            freqs = [sp.nsimplify(f) for f in self.frequencies]
        else:
            freqs = [sp.Integer(k) for k in range(1, self.n_frequencies + 1)]
        if not (self.include_sin or self.include_cos):
            raise ParameterError("FourierLibrary needs include_sin or include_cos to be True")
        return freqs

    def _n_features(self, k: int) -> int:
        n = self.n_frequencies if self.frequencies is None else len(self.frequencies)
        return n * k * (int(self.include_sin) + int(self.include_cos))

    def _expressions(self, symbols):
        self._plan = []
        exprs = []
        for k in self._freqs():
            for j, s in enumerate(symbols):
                for use, fn, np_fn in ((self.include_sin, sp.sin, np.sin),
                                       (self.include_cos, sp.cos, np.cos)):
                    if use:
                        exprs.append(fn(k * s))
                        self._plan.append((np_fn, float(k), j))
        return exprs

    def _evaluate(self, Zs):
        return np.column_stack([f(k * Zs[:, j]) for f, k, j in self._plan])
