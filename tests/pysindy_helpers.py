"""Helpers of the tests that run PySINDy beside this package."""
import warnings

import discrepancy as dc


def pysindy_defaults(**kw):
    """Our model with PySINDy's defaults: finite differences and STLSQ(threshold=0.1)."""
    kw.setdefault("optimizer", dc.STLSQ(threshold=0.1))
    kw.setdefault("differentiation_method", dc.FiniteDifference())
    return dc.DiscrepancyModel(**kw)


def quiet(f, *args, **kwargs):
    """``f(*args, **kwargs)`` with warnings silenced (PySINDy's convergence chatter)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return f(*args, **kwargs)
