"""Error measures of an energy discrepancy model, as percentages."""
from __future__ import annotations

import numpy as np


def percent_error(delta_h: np.ndarray, delta_h_model: np.ndarray, *,
                  normaliser: str = "max") -> np.ndarray:
    """``(dH - dH_model) / scale * 100`` (%), shape ``(m,)``.

    ``normaliser="max"`` is the paper's ``scale = max|dH|``; ``"range"`` uses the window's own
    ``max(dH) - min(dH)``, the honest scale on a validation window that starts late, where
    ``max|dH|`` includes all energy dissipated before the window.
    """
    delta_h, delta_h_model = np.asarray(delta_h, float), np.asarray(delta_h_model, float)
    scale = np.max(np.abs(delta_h)) if normaliser == "max" else np.ptp(delta_h)
    return (delta_h - delta_h_model) / scale * 100.0


def error_summary(delta_h: np.ndarray, delta_h_model: np.ndarray) -> dict[str, float]:
    """Max-abs and RMS percentage errors under both normalisers, plus the scales (J)."""
    out = {}
    for norm in ("max", "range"):
        e = percent_error(delta_h, delta_h_model, normaliser=norm)
        out[f"max_abs_percent_of_{norm}"] = float(np.max(np.abs(e)))
        out[f"rms_percent_of_{norm}"] = float(np.sqrt(np.mean(e ** 2)))
    out["max_abs_delta_h_J"] = float(np.max(np.abs(delta_h)))
    out["range_delta_h_J"] = float(np.ptp(delta_h))
    out["max_abs_error_J"] = float(np.max(np.abs(np.asarray(delta_h) - delta_h_model)))
    return out
