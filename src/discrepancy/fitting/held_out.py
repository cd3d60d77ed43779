"""Forecast windows kept beside the Gram statistics, and the range of every variable.

A fit's statistics are sums, so they stream; scoring a model by its forecasts needs
samples. While the statistics accumulate, :class:`HeldOutWindows` keeps a bounded number
of short windows of the raw data. Each window's origin is the first sample of a
cross-validation segment, so it lies in one fold, and the candidates that forecast from it
are refitted on the statistics of the other folds (the total minus that fold's sums): the
block the forecast starts in was never seen by the coefficients. A window holds up to
:data:`MAX_LEAD` samples after its origin (the longest forecast; later samples belong to
other folds) and ``pre`` samples before it (what smoothing the origin state needs).

The windows kept depend only on the sequence of origins (thinned to every other one when
more than ``2 * MAX_WINDOWS`` are held), so the same data give the same windows whether
they arrive whole, in chunks or from Dask blocks; a Dask fit registers the origins first
and slices only the kept windows out of its arrays. Memory: at most ``2 * MAX_WINDOWS``
windows of ``pre + MAX_LEAD + 1`` samples. The extremes of every state and input seen
(``low``, ``high``) travel with them: the region a fitted model's terms know.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

#: longest forecast kept, in samples after the origin
MAX_LEAD = 1024
#: windows kept at most (twice this before thinning to every other one)
MAX_WINDOWS = 32
#: samples before an origin kept for smoothing it when the method has no finite halo
GLOBAL_PRE = 32
#: fewest windows a choice by forecasts needs (:mod:`discrepancy.selection.choice`)
MIN_WINDOWS = 4


@dataclass(eq=False)
class Window:
    """Raw samples around one forecast origin: times ``(k,)``, states ``(k, n)``, inputs
    ``(k, r)`` or None (allocated at the first samples, ``size`` at most); ``origin``:
    index of the origin sample; ``fold``: the fold its segment belongs to; ``filled``:
    samples held so far."""

    fold: int
    origin: int
    size: int
    t: np.ndarray | None = None
    x: np.ndarray | None = None
    u: np.ndarray | None = None
    filled: int = 0

    @property
    def lead(self) -> int:
        """Samples after the origin."""
        return self.filled - self.origin - 1

    @property
    def full(self) -> bool:
        """True when the window holds ``size`` samples and takes no more."""
        return self.filled >= self.size

    def append(self, t, x, u) -> int:
        """Add consecutive samples (as many as fit); returns how many were taken."""
        if self.t is None:
            self.t, self.x = np.empty(self.size), np.empty((self.size, x.shape[1]))
            self.u = None if u is None else np.empty((self.size, u.shape[1]))
        k = min(len(t), self.size - self.filled)
        a = self.filled
        self.t[a:a + k], self.x[a:a + k] = t[:k], x[:k]
        if self.u is not None:
            self.u[a:a + k] = u[:k]
        self.filled += k
        return k

    def trimmed(self) -> Window:
        """A new window of only the ``filled`` samples held (views of these arrays;
        ``size = filled``)."""
        u = None if self.u is None else self.u[:self.filled]
        return Window(self.fold, self.origin, self.filled, self.t[:self.filled],
                      self.x[:self.filled], u, self.filled)


@dataclass
class HeldOutWindows:
    """Forecast windows and variable extremes collected while statistics accumulate.

    Args:
        segment, n_folds: the statistics' fold layout (row ``i`` is in fold
            ``(i // segment) % n_folds``).
        pre: samples kept before each origin (the smoothing's halo).
        max_lead: samples kept after each origin.
        spacing: rows between origins (default ``segment``: each segment's first row).

    Feed each trajectory as :meth:`begin` (its first data row), :meth:`add` (consecutive
    samples, any number of calls) and :meth:`end`.
    """

    segment: int
    n_folds: int
    pre: int
    max_lead: int = MAX_LEAD
    max_windows: int = MAX_WINDOWS
    spacing: int | None = None
    windows: list = field(default_factory=list)
    low: np.ndarray | None = None
    high: np.ndarray | None = None

    def __post_init__(self):
        self._open, self._tail, self._row, self._sample = [], None, 0, 0

    # ------------------------------------------------------------------ feeding
    def begin(self, first_row: int) -> None:
        """Start a trajectory whose sample 0 is data row ``first_row``."""
        self._open, self._tail, self._row, self._sample = [], None, int(first_row), 0

    def origins(self, n_samples: int, first_sample: int = 0) -> list[int]:
        """Samples (of the current trajectory) among ``first_sample ...`` + ``n_samples``
        at a multiple of ``spacing`` rows (a segment's start by default) with ``pre``
        samples before them (the smoothing of a trajectory's first samples is an
        extrapolation)."""
        first, step = self._row + first_sample, self.spacing or self.segment
        start = -(-first // step) * step
        return [r - self._row for r in range(start, first + n_samples, step)
                if r - self._row >= self.pre]

    def register(self, sample: int) -> Window:
        """A new (empty) window for the origin at ``sample`` of the current trajectory;
        thins the windows when there are too many."""
        window = Window(((self._row + sample) // self.segment) % self.n_folds, self.pre,
                        self.pre + self.max_lead + 1)
        self.windows.append(window)
        if len(self.windows) > 2 * self.max_windows:
            self.windows = self.windows[::2]
        return window

    def add(self, t: np.ndarray, x: np.ndarray, u: np.ndarray | None) -> None:
        """Consecutive samples of the current trajectory."""
        self._extend_range(x, u)
        starts = [(origin - self._sample, self.register(origin))
                  for origin in self.origins(len(t), self._sample)]
        # only windows that survived the thinning are filled (a long piece registers
        # thousands of origins and keeps at most 2 * max_windows)
        kept = {id(w) for w in self.windows}
        self._open = [w for w in self._open if not w.full and id(w) in kept]
        for w in self._open:
            w.append(t, x, u)
        for j, w in starts:
            if id(w) not in kept:
                continue
            if w.origin:   # the samples before the origin: from the tail, then this piece
                tail_t, tail_x, tail_u = self._joined_tail(t, x, u, j, w.origin)
                w.append(tail_t[-w.origin:], tail_x[-w.origin:],
                         None if tail_u is None else tail_u[-w.origin:])
            w.append(t[j:], x[j:], None if u is None else u[j:])
            self._open.append(w)
        self._keep_tail(t, x, u)
        self._sample += len(t)

    def end(self) -> None:
        """The current trajectory is complete."""
        self._open, self._tail = [], None

    def _joined_tail(self, t, x, u, j, need):
        """The last ``need`` samples before sample ``j`` of this piece, the kept tail of the
        previous pieces first (only those samples are joined: joining the whole piece for
        every origin made a 1e6-sample fit spend 5 s here)."""
        lo = max(0, j - need)
        parts = [(t[lo:j], x[lo:j], None if u is None else u[lo:j])]
        if self._tail is not None:
            parts.insert(0, self._tail)
        joined = [np.concatenate([p[k] for p in parts]) if parts[0][k] is not None else None
                  for k in range(3)]
        return joined

    def _keep_tail(self, t, x, u):
        if not self.pre:
            return
        tt, xx, uu = self._joined_tail(t, x, u, len(t), self.pre)
        self._tail = (tt[-self.pre:].copy(), xx[-self.pre:].copy(),
                      None if uu is None else uu[-self.pre:].copy())

    def _extend_range(self, x, u):
        if not len(x):
            return
        # column by column: numpy reduces a tall, narrow array along axis 0 five times slower
        columns = [*x.T, *([] if u is None else u.T)]
        low = np.array([c.min() for c in columns])
        high = np.array([c.max() for c in columns])
        self.low = low if self.low is None else np.minimum(self.low, low)
        self.high = high if self.high is None else np.maximum(self.high, high)

    # ------------------------------------------------------------------ merging
    def merge(self, other: HeldOutWindows) -> None:
        """Add ``other``'s windows (after these) and extremes, in place."""
        for w in other.windows:
            self.windows.append(w)
            if len(self.windows) > 2 * self.max_windows:
                self.windows = self.windows[::2]
        for name in ("low", "high"):
            mine, theirs = getattr(self, name), getattr(other, name)
            if theirs is not None:
                op = np.minimum if name == "low" else np.maximum
                setattr(self, name, theirs.copy() if mine is None else op(mine, theirs))

    def empty_like(self) -> HeldOutWindows:
        """A new collector with the same settings (segment, folds, samples before an origin,
        longest lead, most windows, spacing) and no windows or extremes yet."""
        return HeldOutWindows(self.segment, self.n_folds, self.pre, self.max_lead,
                              self.max_windows, self.spacing)

    def complete(self) -> list[Window]:
        """The kept windows with at least one sample after the origin, trimmed."""
        return [w.trimmed() for w in self.windows if w.lead >= 1]

    def extend_range(self, low: np.ndarray, high: np.ndarray) -> None:
        """Widen the recorded extremes (from data not fed through :meth:`add`)."""
        self._extend_range(np.vstack([low, high]), None)
