"""The small contract every system shares, so experiments and users treat them alike."""
from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable

import numpy as np

from ..errors import ParameterError

# The paper's Table 1 (SI units): the double pendulum of Sections IV.B and IV.C. One source
# for the defaults of both pendulum parameter classes, whose fields differ.
PAPER_TABLE_1 = {"m1": 0.2704, "m2": 0.2056, "a1": 0.1910, "a2": 0.1621, "l1": 0.2667,
                 "I1": 0.003, "I2": 0.0011, "k1": 7.24e-4, "k2": 1.65e-4, "g": 9.818}


class System(ABC):
    """A dynamical system with true dynamics and, where the paper has one, a flawed prior.

    Concrete systems set ``state_names`` and ``input_names`` and implement ``rhs``.
    All arrays are ``(m, n)`` with samples along axis 0.
    """

    state_names: tuple[str, ...] = ()
    input_names: tuple[str, ...] = ()

    @abstractmethod
    def rhs(self, x: np.ndarray, u: np.ndarray | None = None) -> np.ndarray:
        """True dynamics ``dx/dt``, ``(m, n)`` for ``x`` ``(m, n)`` and ``u`` ``(m, r)``."""

    def energy(self, x: np.ndarray) -> np.ndarray:
        """Model energy ``H_m`` ``(m,)`` (J) where the system has one."""
        raise NotImplementedError(f"{type(self).__name__} has no energy function")

    def flawed_model(self) -> Callable[[np.ndarray, np.ndarray | None], np.ndarray]:
        """The paper's imperfect prior ``f_m(x, u)``."""
        raise NotImplementedError(f"{type(self).__name__} has no flawed model")

    @property
    def n_states(self) -> int:
        """Number of states ``n``."""
        return len(self.state_names)


def check_physical_parameters(params, *, may_be_zero=("k1", "k2")) -> None:
    """Validate a frozen dataclass of physical constants in place.

    Every field must be a finite number, > 0 (>= 0 for the names in ``may_be_zero``,
    e.g. friction coefficients); values are stored as floats.
    """
    from dataclasses import fields

    for f in fields(params):
        value = getattr(params, f.name)
        number = isinstance(value, (int, float, np.floating, np.integer)) and \
            not isinstance(value, bool)
        bound = ">= 0" if f.name in may_be_zero else "> 0"
        if not number or not np.isfinite(value) or value < 0 or \
                (value == 0 and f.name not in may_be_zero):
            raise ParameterError(f"{type(params).__name__}.{f.name} must be a finite number "
                                 f"{bound}; got {value!r}")
        object.__setattr__(params, f.name, float(value))


def scaled_parameters(params, factors):
    """A copy of the frozen dataclass ``params`` with each named field multiplied by
    ``factors[name]`` (a mapping); ParameterError names unknown fields."""
    from dataclasses import fields, replace

    valid = [f.name for f in fields(params)]
    unknown = set(factors) - set(valid)
    if unknown:
        raise ParameterError(f"factors has unknown parameter names {sorted(unknown)}; valid: "
                             f"{valid}")
    return replace(params, **{k: getattr(params, k) * float(v) for k, v in factors.items()})
