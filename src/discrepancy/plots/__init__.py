"""Figures of fits and uncertainty (matplotlib, the ``[plots]`` extra).

The backend is the caller's choice: nothing here calls ``matplotlib.use``. Nothing outside
this package imports matplotlib.
"""
from .._optional import require

require("matplotlib", purpose="discrepancy.plots")
