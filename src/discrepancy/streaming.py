"""Chunked fitting, as users call it: ``model.fit(chunks)`` (the machinery, which knows no
model, is :mod:`discrepancy.fitting.streaming`; what a chunk is and how a stream stays
exact are explained there)."""
from __future__ import annotations

from .data.chunks import Chunk, ChunkSource, IterableSource
from .fitting import streaming
from .fitting.streaming import stream_statistics

__all__ = ["Chunk", "ChunkSource", "IterableSource", "chunk_statistics", "stream_statistics"]


def chunk_statistics(model, x, *, t=None, u=None, x_dot=None):
    """``(setup, stats)``: the Gram statistics of chunked ``x`` with ``model``'s set-up
    (what ``model.fit(x)`` solves)."""
    return streaming.chunk_statistics(model.make_setup, model.differentiation_method, x, t=t,
                                      u=u, x_dot=x_dot)
