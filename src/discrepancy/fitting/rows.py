"""The regression's rows: how one trajectory becomes ``(z, y, x_dot)``, one form per kind of fit.

A fit regresses a target ``y`` on the library Θ; what the target is decides everything
else about the rows. Each form answers the same questions (:class:`RowForm`), so the set-up
(:class:`~discrepancy.fitting.setup.FitSetup`) and the forecasts that choose terms
(:mod:`discrepancy.selection`) ask the form instead of testing which kind of fit it is:

* :class:`DerivativeRows` (an ODE, pointwise): the smoothed states ``[x, u]`` and
  ``y = x_dot - f_m(x, u)`` at every sample the differentiation method defines;
* :class:`WeakRows` (an ODE, weak form, :class:`~discrepancy.differentiation.WeakForm`):
  states, prior and library integrated against a bump around each sample, so ``z`` is
  already Θ;
* :class:`NextSampleRows` (a map ``x[k+1] = f_m + g``): ``y = x[k+1] - f_m(x[k], u[k])``.

With measured derivatives (``x_dot`` given) every continuous-time form takes them as they
are, pointwise (:func:`pointwise_rows`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..data.trajectory import Trajectory
from ..differentiation import Differentiator, WeakForm
from ..resources import CHUNKED, check_memory, n_bytes
from .discrete import discrete_rows
from .held_out import GLOBAL_PRE


def copy_into(theta: np.ndarray, *, out: np.ndarray | None = None) -> np.ndarray:
    """The ``transform`` of rows that are Θ already (the weak form): ``theta`` itself, or
    copied into ``out``."""
    if out is None:
        return theta
    out[...] = theta
    return out


@dataclass(frozen=True)
class RowForm:
    """The questions every form answers (abstract: the hooks are :meth:`rows`,
    :attr:`pre`; the rest has defaults). ``differentiation``: the fit's method."""

    differentiation: Differentiator
    #: forecasts start from the raw sample at their origin (not from smoothed states)
    raw_origins = False

    def rows(self, setup, trajectory: Trajectory):
        """``(z, y, x_dot)`` of one trajectory (``setup``: its prior, library, sizes)."""
        raise NotImplementedError

    @property
    def pre(self) -> int:
        """Samples a forecast window keeps before its origin (what smoothing it needs)."""
        raise NotImplementedError

    def kept(self, trajectory: Trajectory) -> slice:
        """The samples that give rows: all but the ends a method with ``drop_endpoints``
        leaves undefined (all of them when ``x_dot`` is measured)."""
        if trajectory.x_dot is not None:
            return slice(None)
        first, last = self.differentiation.dropped_rows
        return slice(first, trajectory.n_samples - last)

    def transform(self, library):
        """Turns ``z`` into Θ (``transform(z, out=...)``)."""
        return library.transform

    def variables(self, names: list[str]) -> list[str]:
        """The names of ``z``'s columns (for messages about the data)."""
        return names


def pointwise_rows(form: RowForm, setup, trajectory: Trajectory):
    """``(z, y, x_dot)`` from derivatives at each sample: ``[x_smooth, u]`` ``(m, n + r)``,
    ``x_dot - f_m`` and ``x_dot`` ``(m, n)`` over the kept samples (measured ``x_dot``
    taken as it is)."""
    u = trajectory.u
    if trajectory.x_dot is None:
        xs, xd = form.differentiation.smooth_and_differentiate(trajectory.x, trajectory.t)
        kept = form.kept(trajectory)  # ends a method leaves undefined (drop_endpoints)
        xs, xd, u = xs[kept], xd[kept], None if u is None else u[kept]
    else:
        xs, xd = trajectory.x, trajectory.x_dot
    y = xd - setup.prior(xs, u)
    z = xs if u is None else np.hstack([xs, u])
    return z, y, xd


@dataclass(frozen=True)
class DerivativeRows(RowForm):
    """Rows from derivatives estimated at each sample by ``differentiation`` (or measured)."""

    def rows(self, setup, trajectory: Trajectory):
        """See :func:`pointwise_rows`."""
        return pointwise_rows(self, setup, trajectory)

    @property
    def pre(self) -> int:
        """The smoothing's halo (every sample before the origin for a global method)."""
        halo = self.differentiation.halo
        return GLOBAL_PRE if halo is None else int(halo)


@dataclass(frozen=True)
class WeakRows(RowForm):
    """Rows of the weak form: every quantity integrated against each sample's test
    function (``differentiation`` is a :class:`~discrepancy.differentiation.WeakForm`)."""

    raw_origins = True

    def rows(self, setup, trajectory: Trajectory):
        """``(Θ integrated, by-parts term - integrated prior, by-parts term)``; measured
        ``x_dot`` is taken pointwise."""
        if trajectory.x_dot is not None:
            return pointwise_rows(self, setup, trajectory)
        x, u = trajectory.x, trajectory.u
        check_memory(f"the weak form's integrals of {len(x)} samples and {setup.n_features} "
                     "columns", 3 * n_bytes((len(x), setup.n_features + setup.n_states)),
                     f"Pass the trajectory in pieces: {CHUNKED}")
        theta = setup.library.transform(x if u is None else np.hstack([x, u]))
        values = np.hstack([theta, setup.prior(x, u)])
        integral, by_parts = self.differentiation.rows(x, trajectory.t, values)
        p = theta.shape[1]
        return integral[:, :p], by_parts - integral[:, p:], by_parts

    def transform(self, library):
        """The rows are Θ already: copied as they are."""
        return copy_into

    @property
    def pre(self) -> int:
        """None: a weak-form forecast starts from the raw sample at its origin."""
        return 0

    def variables(self, names: list[str]) -> list[str]:
        """None: the rows hold integrated columns, not the variables."""
        return []


@dataclass(frozen=True)
class NextSampleRows(RowForm):
    """Rows of a map: each sample paired with the next (``differentiation`` is
    :class:`~discrepancy.fitting.discrete.NextSample`)."""

    raw_origins = True

    def rows(self, setup, trajectory: Trajectory):
        """``(z, x[k+1] - f_m, x[k+1])``, see
        :func:`~discrepancy.fitting.discrete.discrete_rows`."""
        return discrete_rows(setup, trajectory)

    def kept(self, trajectory: Trajectory) -> slice:
        """Every sample (a map's last sample simply has no successor)."""
        return slice(None)

    @property
    def pre(self) -> int:
        """None: a map's forecast starts from the raw sample at its origin."""
        return 0


def row_form(differentiation: Differentiator, *, discrete_time: bool) -> RowForm:
    """The form of a fit's rows: a map's, the weak form's, or pointwise derivatives'."""
    if discrete_time:
        return NextSampleRows(differentiation)
    if isinstance(differentiation, WeakForm):
        return WeakRows(differentiation)
    return DerivativeRows(differentiation)
