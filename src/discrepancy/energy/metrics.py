"""Error measures of an energy discrepancy model, as percentages."""
from __future__ import annotations

import numpy as np

from ..data.validation import check_array
from ..errors import DataError, ParameterError


def _paired(delta_h, delta_h_model) -> tuple[np.ndarray, np.ndarray]:
    """Both energy series as finite ``(m,)`` vectors of one length ``m >= 1``."""
    delta_h = check_array("delta_h", delta_h, ndim=1)
    if delta_h.size == 0:
        raise DataError("delta_h must hold at least one sample; got an empty array")
    return delta_h, check_array("delta_h_model", delta_h_model, ndim=1, n_rows=len(delta_h))


def percent_error(delta_h: np.ndarray, delta_h_model: np.ndarray, *,
                  normaliser: str = "max") -> np.ndarray:
    """``(dH - dH_model) / scale * 100`` (%), shape ``(m,)``.

    ``normaliser="max"`` is the paper's ``scale = max|dH|``; ``"range"`` uses the window's own
    ``max(dH) - min(dH)``, the honest scale on a validation window that starts late, where
    ``max|dH|`` includes all energy dissipated before the window.
    """
    if normaliser not in ("max", "range"):
        raise ParameterError(f"normaliser must be 'max' or 'range'; got {normaliser!r}")
    delta_h, delta_h_model = _paired(delta_h, delta_h_model)
    scale = np.max(np.abs(delta_h)) if normaliser == "max" else np.ptp(delta_h)
    if scale == 0:
        raise DataError(f"delta_h has no {'size' if normaliser == 'max' else 'range'} to "
                        f"normalise by (it is constant at {delta_h[0]:g} J)")
    return (delta_h - delta_h_model) / scale * 100.0


def error_summary(delta_h: np.ndarray, delta_h_model: np.ndarray) -> dict[str, float]:
    """Max-abs and RMS percentage errors under both normalisers, plus the scales (J)."""
    delta_h, delta_h_model = _paired(delta_h, delta_h_model)
    out = {}
    for norm in ("max", "range"):
        e = percent_error(delta_h, delta_h_model, normaliser=norm)
        out[f"max_abs_percent_of_{norm}"] = float(np.max(np.abs(e)))
        out[f"rms_percent_of_{norm}"] = float(np.sqrt(np.mean(e ** 2)))
    out["max_abs_delta_h_J"] = float(np.max(np.abs(delta_h)))
    out["range_delta_h_J"] = float(np.ptp(delta_h))
    out["max_abs_error_J"] = float(np.max(np.abs(np.asarray(delta_h) - delta_h_model)))
    return out
