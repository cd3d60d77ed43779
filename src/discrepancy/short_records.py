"""What the automatic choices do with records too short for them.

The defaults choose from the data: the smoothing window by generalized cross-validation
(:class:`~discrepancy.differentiation.AutoSmoothing`, which needs a few windows of samples)
and the sparsity by cross-validation over contiguous blocks (``STLSQ(threshold="auto")``,
which needs at least two blocks). PySINDy's own examples and tests use records of ten or a
dozen samples, on which neither choice can be made. Refusing such data would make the
defaults fail where PySINDy's work, so each automatic choice asks :func:`too_short` first
and, below what it needs, falls back to what needs no held-out data (finite differences, an
information criterion), with a :class:`~discrepancy.errors.ShortRecordWarning` that says what
was used and why. Choosing the method yourself silences it.
"""
from __future__ import annotations

import warnings

from .errors import ShortRecordWarning


def too_short(choice: str, have: int, need: int, *, unit: str = "samples",
              fallback: str) -> bool:
    """Whether ``have`` is below the ``need`` of the automatic ``choice``; if so, warns that
    ``fallback`` is used instead (the warning points at the caller's line outside this
    package). Any automatic choice (a selection rule, a smoother) calls it with its own
    requirement, so short records degrade the same way everywhere."""
    if have >= need:
        return False
    warnings.warn(f"{choice} needs at least {need} {unit}; these data have {have}, so "
                  f"{fallback} is used instead (give longer records, or choose it yourself "
                  "to silence this warning)", ShortRecordWarning, stacklevel=_user_level())
    return True


def _user_level() -> int:
    """The ``stacklevel`` of the first frame outside this package (the user's call)."""
    import sys
    from pathlib import Path

    package = str(Path(__file__).resolve().parent)
    frame, level = sys._getframe(1), 1
    while frame is not None and str(Path(frame.f_code.co_filename).resolve()).startswith(package):
        frame, level = frame.f_back, level + 1
    return level
