"""The frozen set-up of a PDE fit: runs of fields -> regression rows -> Gram statistics.

Rows are grid points at sample times (pointwise form: ``u_t - N_m`` against the library on
the jet ``[u, u_x, ..., inputs]``), or test-function centres (weak form). Either way they go
through the same blocked accumulation as trajectories (:mod:`discrepancy.fitting.accumulate`), with
cross-validation folds made of whole snapshots (segments of consecutive times dealt to the
folds in turn), so the STLSQ threshold is chosen as for ODEs, in memory, streamed from disk
or on Dask alike.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..data.fields import FieldRun, Grid
from ..fitting.accumulate import Names, accumulate, statistics_bytes
from ..fitting.rows import copy_into
from ..libraries import FeatureLibrary
from ..optimizers import GramStatistics, Optimizer
from ..resources import SMALLER_LIBRARY, check_memory
from .prior import FieldPrior
from .variables import FieldVariables
from .weak import FieldWeakForm, WeakPlan, centres, weak_rows

#: most cross-validation segments kept (each holds its own Gram statistics)
MAX_SEGMENTS = 40


def _noise(noise_std, n: int):
    """Noise per field for the weak form's bias correction (``None``: no correction)."""
    if noise_std is None or (np.ndim(noise_std) == 0 and noise_std == 0):
        return None
    return [float(s) for s in noise_std] if len(noise_std) == n else None


@dataclass(frozen=True)
class FieldSetup:
    """Everything a PDE fit needs besides the data, resolved once.

    Attributes:
        variables: the jet variables the library and prior see (their names, orders).
        grid: the grid every run lies on.
        prior: the checked :class:`~discrepancy.pde.prior.FieldPrior`.
        library: the feature library fitted to ``variables.names``.
        optimizer: the sparse regression (a template; fits use copies).
        time_methods: one time differentiator per field (pointwise form), or the
            :class:`~discrepancy.pde.weak.FieldWeakForm` alone.
        spatial: one spatial differentiator per grid axis.
        choice: how data-driven choices were made (``None`` when all were given).
        probe_snapshots: snapshots in the data (or the part read first), sizing the folds.
    """

    variables: FieldVariables
    grid: Grid
    prior: FieldPrior
    library: FeatureLibrary
    optimizer: Optimizer
    time_methods: tuple
    spatial: tuple
    choice: dict | None = None
    probe_snapshots: int = 1000

    @property
    def field_names(self) -> list[str]:
        """Names of the fields, in the order of the last axis of the data."""
        return list(self.variables.fields)

    @property
    def input_names(self) -> list[str]:
        """Names of the inputs (empty when there are none)."""
        return list(self.variables.inputs)

    @property
    def n_fields(self) -> int:
        """Number of fields ``n``."""
        return len(self.variables.fields)

    @property
    def n_features(self) -> int:
        """Number of library columns ``p`` (candidate terms per equation)."""
        return self.library.n_features_

    @property
    def weak(self) -> FieldWeakForm | None:
        """The :class:`~discrepancy.pde.weak.FieldWeakForm` when the fit uses the weak form,
        ``None`` in the pointwise form."""
        method = self.time_methods[0]
        return method if isinstance(method, FieldWeakForm) else None

    @property
    def halo(self) -> int:
        """Time samples on each side a row depends on (``None``: a global method)."""
        halos = [m.halo for m in self.time_methods]
        return None if None in halos else max(halos)

    @property
    def min_samples(self) -> int:
        """Fewest time samples a run needs: the largest demand of the time methods."""
        return max(m.min_samples for m in self.time_methods)

    @cached_property
    def plan(self) -> WeakPlan | None:
        """The weak form's integrals (``None`` in the pointwise form)."""
        if self.weak is None:
            return None
        return WeakPlan.build(self.library.feature_expressions_, self.prior.expressions,
                              self.variables.fields, self.variables.coordinates,
                              _noise(self.weak.noise_std, self.n_fields))

    @property
    def rows_per_snapshot(self) -> int:
        """Regression rows each snapshot contributes: every grid point in the pointwise form,
        the test-function centres on the grid in the weak form."""
        if self.weak is None:
            return self.grid.size

        widths = [int(w) for w in self.weak.widths[1:]]
        strides = self.weak.strides(self.grid)
        return int(np.prod([len(centres(n, w, s, p)) for n, w, s, p in zip(
            self.grid.shape, widths, strides, self.grid.periodic, strict=True)]))

    def rows(self, run: FieldRun) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(z, y, signal)`` of one run (or a piece of one): in the pointwise form the
        variables ``(R, v)``, ``u_t - N_m`` ``(R, n)`` and ``u_t``; in the weak form ``z`` is
        already Θ's integrals. Rows are in time-major order, ``rows_per_snapshot`` per time."""
        if self.weak is not None:
            return self._weak_rows(run)
        smooth, rate = self._time_derivative(run)
        jet = self.variables.jet(smooth, run.inputs, self.grid, self.spatial)
        prior = self.prior.values(smooth, run.inputs, jet, self.variables.names)
        n = self.n_fields
        return (jet.reshape(-1, jet.shape[-1]), (rate - prior).reshape(-1, n),
                rate.reshape(-1, n))

    def _time_derivative(self, run: FieldRun):
        m = run.u.shape[0]
        smooth, rate = np.empty_like(run.u), np.empty_like(run.u)
        for j, method in enumerate(self.time_methods):
            s, r = method.smooth_and_differentiate(run.u[..., j].reshape(m, -1), run.t)
            smooth[..., j], rate[..., j] = s.reshape(run.u.shape[:-1]), r.reshape(
                run.u.shape[:-1])
        return smooth, rate

    def _weak_rows(self, run: FieldRun):
        plan = self.plan
        variables = self.variables.with_order(plan.order)
        jet = variables.jet(run.u, run.inputs, self.grid, self.spatial)
        prior = None
        if not self.prior.is_symbolic and self.prior._call is not None:
            prior = self.prior.values(run.u, run.inputs, None, None)
        return weak_rows(self.weak, plan, run.u, run.inputs, run.t, self.grid, variables.names,
                         jet, self.library.user_functions(), prior)

    @property
    def transform(self):
        """Turns the ``z`` of :meth:`rows` into Θ (``transform(z, out=...)``)."""
        return copy_into if self.weak is not None else self.library.transform

    @cached_property
    def names(self) -> Names:
        variables = [] if self.weak is not None else self.variables.names
        return Names(self.library.get_feature_names(), variables)

    @property
    def segment_snapshots(self) -> int:
        """Snapshots per cross-validation segment: one time window (``2 halo + 1``), or
        more so that there are at most :data:`MAX_SEGMENTS` (see :mod:`.solve`)."""
        window = 2 * (self.halo or 0) + 1
        return max(window, -(-self.probe_snapshots // MAX_SEGMENTS))

    def new_statistics(self) -> GramStatistics:
        """Empty statistics kept per segment of :attr:`segment_snapshots` snapshots (the
        purged cross-validation's blocks, :mod:`discrepancy.pde.solve`)."""

        p, n = self.n_features, self.n_fields
        segments = max(1, -(-self.probe_snapshots // self.segment_snapshots))
        check_memory(f"the Gram statistics of {p} library columns in {segments} segments",
                     statistics_bytes(p, n, segments), SMALLER_LIBRARY)
        return GramStatistics(p, n, segments, self.rows_per_snapshot * self.segment_snapshots)

    def statistics(self, run: FieldRun, *, into: GramStatistics | None = None,
                   keep: slice | None = None) -> GramStatistics:
        """Add one run's statistics to ``into`` (default: new ones); ``keep``: only the
        snapshots in this slice (a chunk's centre, its halo cut off)."""
        stats = self.new_statistics() if into is None else into
        z, y, signal = self.rows(run)
        if keep is not None:
            per = self.rows_per_snapshot
            cut = slice(keep.start * per, keep.stop * per)
            z, y, signal = z[cut], y[cut], signal[cut]
        return accumulate(stats, self.transform, z, y, signal, names=self.names)
