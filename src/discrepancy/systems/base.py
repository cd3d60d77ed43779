"""The small contract every system shares, so experiments and users treat them alike."""
from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable

import numpy as np


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
        return len(self.state_names)
