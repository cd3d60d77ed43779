"""The frozen fit set-up: everything a fit needs besides the data, resolved once.

A :class:`FitSetup` turns one trajectory into the regression's Gram statistics
(derivative -> residual ``x_dot - f_m`` -> library Θ -> ``ΘᵀΘ``, ``Θᵀy``, ``yᵀy``). It is
the seam between the model and the ways data arrive: the in-memory fit, the chunked stream
(:mod:`discrepancy.fitting.streaming`) and Dask (:mod:`discrepancy.fitting.distributed`) all
compute statistics with the same set-up and hand them to the model's ``fit_statistics``. The
set-up knows no model: the model resolves its parameters into one
(:func:`discrepancy.models.core.resolve.resolve_setup`).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..data.trajectory import Trajectory
from ..differentiation import Differentiator, get_differentiation_method
from ..errors import ShapeError
from ..libraries import FeatureLibrary
from ..optimizers import GramStatistics, Optimizer
from ..optimizers.resampling import Rows
from ..resources import SMALLER_LIBRARY, check_memory, n_bytes
from ..symbolic import IDENTIFIER
from .accumulate import BLOCK_ROWS, Names, accumulate, statistics_bytes
from .held_out import MIN_WINDOWS, HeldOutWindows
from .prior import Prior
from .rows import RowForm, row_form

#: cross-validation folds kept in the statistics (contiguous segments dealt out in turn)
N_FOLDS = 5
#: segments are at most this long when the data allow two per fold (long segments keep the
#: accumulation's products large; short data need shorter segments to have folds at all)
MIN_SEGMENT = 512
#: the data rows looked at to size the segments (the same prefix in memory and streamed)
FOLD_PROBE_ROWS = 2 * N_FOLDS * MIN_SEGMENT


@dataclass(frozen=True)
class FitSetup:
    """Names, prior, fitted library, optimizer template and differentiation for a fit.

    Attributes:
        state_names, input_names: names of the ``n`` states and ``r`` inputs.
        prior: the checked prior ``f_m``.
        library: the feature library, bound to ``[*state_names, *input_names]``.
        optimizer: the sparse regression (a template; fits work on copies).
        differentiation: turns measured states into ``(x_smooth, x_dot)`` (a method chosen
            from the data is already resolved here).
        choice: how a data-driven differentiation method was resolved (``None`` when the
            method was given), e.g. ``{"chosen_by": "GCV", "noise_std": [...], ...}``.
    """

    state_names: tuple[str, ...]
    input_names: tuple[str, ...]
    prior: Prior
    library: FeatureLibrary
    optimizer: Optimizer
    differentiation: Differentiator
    choice: dict | None = None
    discrete_time: bool = False
    probe_rows: int = FOLD_PROBE_ROWS

    @property
    def variable_names(self) -> list[str]:
        """``[*state_names, *input_names]``: the variables ``z`` the library acts on."""
        return [*self.state_names, *self.input_names]

    @property
    def n_states(self) -> int:
        """Number of states ``n``."""
        return len(self.state_names)

    @property
    def n_inputs(self) -> int:
        """Number of inputs ``r``."""
        return len(self.input_names)

    @property
    def n_features(self) -> int:
        """Number of library columns ``p``."""
        return self.library.n_features_

    @cached_property
    def form(self) -> RowForm:
        """How a trajectory becomes rows: pointwise derivatives, the weak form or a map's
        next sample (:mod:`discrepancy.fitting.rows`)."""
        return row_form(self.differentiation, discrete_time=self.discrete_time)

    def rows(self, trajectory: Trajectory) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(z, y, x_dot)`` of one trajectory: what :attr:`transform` turns into the
        regression's rows of Θ (the variables ``[x_smooth, u]`` ``(m, n + r)``), the
        residual ``x_dot - f_m`` ``(m, n)`` and the derivatives ``(m, n)``. In the weak form
        (:class:`~discrepancy.differentiation.WeakForm`) every quantity is integrated against
        each sample's test function instead, and ``z`` is already Θ."""
        return self.form.rows(self, trajectory)

    def row_weights(self, trajectory: Trajectory) -> np.ndarray | None:
        """The sample weights from the first of :meth:`rows`' rows on (``None`` when
        unweighted; a map's last sample, which has no successor, gives no row)."""
        if trajectory.weight is None:
            return None
        return trajectory.weight[self.form.kept(trajectory)]

    @property
    def transform(self):
        """Turns the ``z`` of :meth:`rows` into Θ (``transform(z, out=...)``)."""
        return self.form.transform(self.library)

    def residual(self, trajectory: Trajectory) -> tuple[np.ndarray, np.ndarray]:
        """``(z, y)``: variables ``[x_smooth, u]`` ``(m, n + r)`` and ``x_dot - f_m``
        ``(m, n)`` of one trajectory."""
        return self.rows(trajectory)[:2]

    @property
    def fold_segment(self) -> int:
        """Rows per contiguous cross-validation segment: a power of two of at least twice
        the differentiation window (residuals of neighbouring rows are correlated over
        about one window) and of ``MIN_SEGMENT`` (512) or, for short data (``probe_rows``,
        the rows of the first ``FOLD_PROBE_ROWS`` seen), of a tenth of them; at most one
        accumulation block."""
        need = max(self._short_segment, 2 * (2 * self._halo + 1))
        return min(BLOCK_ROWS, 1 << (need - 1).bit_length())

    @property
    def origin_spacing(self) -> int:
        """Rows between forecast origins: a segment's, unless the data are known to be short
        (fewer than ``FOLD_PROBE_ROWS`` rows) and the smoothing window stretched the
        segments so far that they hold fewer than ``MIN_WINDOWS`` origins; then one
        smoothing window (at least the short data's segment), so forecasts can still judge
        (a pendulum of 3001 samples smoothed by 309 has segments of 1024: two origins).
        Windows from such origins also run into the next segment, as long windows do."""
        segment = self.fold_segment
        if self.probe_rows >= FOLD_PROBE_ROWS or (self.probe_rows - 1) // segment >= \
                MIN_WINDOWS:
            return segment
        return max(self._short_segment, 2 * self._halo + 1)

    @property
    def _halo(self) -> int:
        return self.differentiation.halo or 0

    @property
    def _short_segment(self) -> int:
        short = max(16, 1 << (max(1, self.probe_rows // (2 * N_FOLDS)).bit_length() - 1))
        return min(MIN_SEGMENT, short)

    def new_statistics(self) -> GramStatistics:
        """Empty statistics of the right size (``p`` features, ``n`` targets), kept per
        cross-validation fold as well (:data:`N_FOLDS` folds of ``fold_segment`` rows).
        Raises ResourceError when a fit's statistics would not fit in memory."""
        p, n = self.n_features, self.n_states
        check_memory(f"the Gram statistics of {p} library columns", statistics_bytes(p, n),
                     SMALLER_LIBRARY + "; they are p x p, so chunked fitting does not help")
        stats = GramStatistics(p, n, N_FOLDS, self.fold_segment)
        stats.held_out = self.new_held_out()
        return stats

    def new_held_out(self):
        """Empty forecast windows for these statistics' folds (see
        :mod:`discrepancy.fitting.held_out`); ``pre``: the smoothing's halo (none for maps
        and the weak form, whose origins are raw samples)."""
        return HeldOutWindows(self.fold_segment, N_FOLDS, self.form.pre,
                              spacing=self.origin_spacing)

    @cached_property
    def names(self):
        """Names of Θ's columns and of the variables, for messages about the data."""
        return Names(self.library.get_feature_names(), self.form.variables(self.variable_names))

    def statistics(self, trajectory: Trajectory, *,
                   into: GramStatistics | None = None) -> GramStatistics:
        """Add one trajectory's statistics to ``into`` (default: new ones); returns them.

        Rows go through the fixed block grid of :mod:`discrepancy.fitting.accumulate`, so the sums
        do not depend on how the rows arrive (whole, in chunks, on Dask workers).
        """
        stats = self.new_statistics() if into is None else into
        z, y, x_dot = self.rows(trajectory)
        weight = self.row_weights(trajectory)
        weight = None if weight is None else weight[:len(z)]
        if stats.held_out is not None:   # forecast windows, in the rows' numbering
            stats.held_out.begin(stats.count)
            stats.held_out.add(trajectory.t, trajectory.x, trajectory.u)
            stats.held_out.end()
        first = stats.count
        accumulate(stats, self.transform, z, y, x_dot, weight, names=self.names)
        if self.optimizer.needs_rows:  # trimming or bagging samples: keep the rows too
            self._keep_rows(stats, z, y, x_dot, weight, first)
        return stats

    def _keep_rows(self, stats, z, y, x_dot, weight, first: int) -> None:
        check_memory(f"the {len(z)} rows of Θ that {self.optimizer!r} needs",
                     n_bytes((len(z), self.n_features)), "Use a smaller library or fewer "
                     "samples, or a solver that works on the statistics alone")
        fold = ((first + np.arange(len(z))) // stats.segment) % stats.n_folds
        rows = Rows(self.transform(z), y, x_dot, weight, fold)
        stats.rows = rows if stats.rows is None else stats.rows + rows


def resolve_names(arg: str, given, k: int, stem: str, *, one) -> list[str]:
    """``k`` variable names: the given ones (checked) or ``stem1 ... stemk`` (``one`` when
    ``k == 1`` and given)."""
    if given is None:
        return [one] if k == 1 and one else [f"{stem}{i + 1}" for i in range(k)]
    names = [given] if isinstance(given, str) else list(given)
    if len(names) != k:
        raise ShapeError(f"{arg} must have {k} names (one per column of the data); "
                         f"got {len(names)}: {names}")
    bad = [n for n in names if not isinstance(n, str) or not IDENTIFIER.match(n)]
    if bad or len(set(names)) != len(names):
        raise ShapeError(f"{arg} must be distinct identifiers (letters, digits, _); got {names}")
    return names


def sample_rows(differentiation_method) -> int:
    """Rows read before the set-up is made: what a data-driven ``differentiation_method``
    (a Differentiator or a spec) looks at, and at least what sizes the cross-validation
    segments (:data:`FOLD_PROBE_ROWS`)."""
    method = get_differentiation_method(differentiation_method)
    own = int(method.sample_rows) if getattr(method, "data_driven", False) else 0
    return max(own, FOLD_PROBE_ROWS)
