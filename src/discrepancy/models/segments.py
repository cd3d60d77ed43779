"""Records cut into shooting segments: which samples each segment covers and fits.

Multiple shooting runs every record as consecutive segments of ``length`` steps, each from
a state of its own; the end of a segment must meet the start of the next (a continuity
constraint of the fit). A segment covers samples ``first .. first + steps`` of its record
(``steps <= length``; a short last segment is padded with steps of length 0, which change
nothing) and fits the residuals of samples ``first .. first + steps - 1``, plus its last
sample when it is the record's last segment, so every fitted sample counts exactly once.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: samples per segment when the caller does not say
DEFAULT_LENGTH = 128


@dataclass
class SegmentLayout:
    """Segments of a set of records (arrays over the ``N`` segments).

    Attributes:
        length: steps per segment ``L`` (the padded length).
        record, first, steps: record index, first sample and real steps of each ``(N,)``.
        last: ``(N,)`` bool, the record's last segment (no continuity constraint after).
        cols, lengths: stage inputs ``(N L, r (2S+1))`` and step lengths ``(N L,)``.
        y: outputs ``(N, L + 1, k)`` at the segment's samples (0 where padded).
        weight: ``(N, L + 1)`` 1.0 where the residual counts, else 0.
    """

    length: int
    record: np.ndarray
    first: np.ndarray
    steps: np.ndarray
    last: np.ndarray
    cols: np.ndarray
    lengths: np.ndarray
    y: np.ndarray
    weight: np.ndarray

    @property
    def count(self) -> int:
        """Number of segments ``N``."""
        return len(self.record)

    @property
    def links(self) -> np.ndarray:
        """``(N,)`` bool: segments whose end must meet the next segment's start."""
        return ~self.last

    def starts_of(self, record: int) -> np.ndarray:
        """Indices of the segments of ``record`` in order."""
        return np.flatnonzero(self.record == record)

    def first_segments(self) -> np.ndarray:
        """Index of the first segment of every record ``(R,)``."""
        return np.flatnonzero(np.r_[True, self.record[1:] != self.record[:-1]])

    def batches(self, size: int):
        """Slices of at most ``size`` consecutive segments."""
        for first in range(0, self.count, size):
            yield slice(first, min(first + size, self.count))


def layout(records, rows, length: int, shooting) -> SegmentLayout:
    """Segments of ``length`` steps over the fitted samples of every record.

    ``rows[i]``: bool ``(m_i,)``, the samples of record ``i`` whose residuals count; the
    segments cover the record up to its last such sample."""
    spans = []
    for i, w in enumerate(rows):
        end = int(np.flatnonzero(w)[-1]) if w.any() else 0
        length_i = max(1, min(length, end))
        for first in range(0, max(end, 1), length_i):
            spans.append((i, first, min(length_i, end - first), first + length_i >= end))
    L = max(s[2] for s in spans) if spans else 1
    L = max(L, 1)
    N = len(spans)
    k = records[0].y.shape[1]
    cols = np.zeros((N * L, shooting.r * (2 * shooting.substeps + 1)))
    lengths = np.zeros(N * L)
    y = np.zeros((N, L + 1, k))
    weight = np.zeros((N, L + 1))
    for j, (i, first, steps, is_last) in enumerate(spans):
        record, w = records[i], rows[i]
        c, h = shooting.columns(record.stages[first:first + steps] if shooting.r else None,
                                record.h[first:first + steps], L)
        cols[j * L:(j + 1) * L] = c[:L]
        lengths[j * L:(j + 1) * L] = h[:L]
        stop = first + steps + (1 if is_last else 0)
        y[j, :stop - first] = record.y[first:stop]
        weight[j, :stop - first] = w[first:stop]
    record, first, steps, last = (np.array([s[n] for s in spans]) for n in range(4))
    return SegmentLayout(L, record, first, steps, last.astype(bool), cols, lengths, y, weight)
