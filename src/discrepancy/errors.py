"""Exceptions raised by discrepancy.

Every error is a :class:`DiscrepancyError` and also a subclass of the builtin
exception a Python user would expect (``ValueError`` for bad values,
``RuntimeError`` for solver failures), so ``except ValueError`` keeps working.
Messages name the argument, what was expected and what was given.
"""
import sys


class DiscrepancyError(Exception):
    """Base class of every error raised on purpose by this package."""


class ShapeError(DiscrepancyError, ValueError):
    """An array has the wrong number of dimensions, rows or columns."""


class DataError(DiscrepancyError, ValueError):
    """Data values are unusable: NaN/inf, non-increasing times, implausible ranges."""


class ParameterError(DiscrepancyError, ValueError):
    """A constructor or method argument is out of its valid range."""


class UnknownNameError(ParameterError):
    """A name (method, variable, dataset) is not one of the valid ones (a ParameterError)."""


class NotFittedError(DiscrepancyError, AttributeError):
    """A method that needs a fitted model was called before ``fit``.

    When scikit-learn is imported (as it is wherever its ``NotFittedError`` can be caught,
    e.g. ``sklearn.utils.validation.check_is_fitted``), the error raised is also an instance
    of ``sklearn.exceptions.NotFittedError``; scikit-learn is never imported for this.
    """

    def __new__(cls, *args, **kwargs):
        if cls is NotFittedError:
            cls = _also_sklearn() or cls
        return super().__new__(cls, *args, **kwargs)

    def __reduce__(self):
        return NotFittedError, self.args   # pickles by the public class, whichever was made


_COMBINED: dict = {}


def _also_sklearn():
    """NotFittedError that is also scikit-learn's, when scikit-learn is already imported."""
    sklearn_errors = sys.modules.get("sklearn.exceptions")
    if sklearn_errors is None:
        return None
    if "class" not in _COMBINED:
        _COMBINED["class"] = type("NotFittedError", (NotFittedError,
                                                     sklearn_errors.NotFittedError),
                                  {"__module__": __name__, "__doc__": NotFittedError.__doc__,
                                   "__qualname__": "NotFittedError"})
    return _COMBINED["class"]


class PriorError(DiscrepancyError, ValueError):
    """The prior model f_m returned something unusable (wrong shape, NaN)."""


class FeatureError(DiscrepancyError, ValueError):
    """A library term could not be evaluated on the data (it raised, or gave NaN/inf);
    the message names the term and the first bad row."""


class ResourceError(DiscrepancyError, MemoryError):
    """The work asked for would not fit in memory (or exceeds a size limit); refused before
    anything large is allocated. The message says how big and what to do instead."""


class MissingFileError(DiscrepancyError, FileNotFoundError):
    """A file or folder given by path does not exist (also a ``FileNotFoundError``)."""


class ModelFileError(DiscrepancyError, ValueError):
    """A model file is not valid JSON of a known version, or was tampered with."""


class ExportError(DiscrepancyError, ValueError):
    """A model cannot be exported to the requested form (e.g. a numpy-only term to CasADi)."""


class InfeasibleError(DiscrepancyError, ValueError):
    """A control problem cannot be met as posed: limits too tight for the task (a rail too
    short for the swing), a horizon too short. The message names the limit or horizon and,
    where it was measured, what the task needs."""


class MissingDependencyError(DiscrepancyError, ImportError):
    """An optional dependency is not installed; the message says which extra installs it."""


class ConvergenceError(DiscrepancyError, RuntimeError):
    """A solver (ODE, optimiser, IPOPT) did not reach a valid solution."""


class SimulationError(ConvergenceError):
    """A simulation stopped early (blow-up, failed step, evaluation budget spent).

    Attributes:
        time: the time it stopped at; state: the state there ``(n,)``;
        partial: the states at the output times reached ``(k', n)``, and ``times`` ``(k',)``.
    """

    def __init__(self, message: str, *, time: float, state, partial, times):
        super().__init__(message)
        self.time, self.state, self.partial, self.times = time, state, partial, times


class ConvergenceWarning(UserWarning):
    """An iterative solver stopped at its iteration limit; its last iterate is used."""


class ShortRecordWarning(UserWarning):
    """A record is too short for an automatic choice (a smoothing window, a cross-validated
    threshold); the message says what was used instead (:mod:`discrepancy.short_records`)."""


class NameConventionWarning(UserWarning):
    """A name refers to a default variable name that means another variable in PySINDy's
    0-based names (``x1`` is the first state here, the second in PySINDy)."""


class InitialStateWarning(UserWarning):
    """Even the best of several starts fits the measured outputs poorly: the estimated
    initial state (and a simulation from it) should not be trusted. The message gives the
    RMS error relative to the outputs' spread."""


class CoarseSamplingWarning(UserWarning):
    """The data have too few samples per period for the chosen differentiation method."""


class CompilationWarning(UserWarning):
    """A function could not be compiled to C and runs in CasADi's virtual machine instead."""
class SelectionWarning(UserWarning):
    """A choice made from the data went against what was asked for or expected (e.g.
    ``refine`` kept the coefficients it started from because the refit forecast worse)."""


class PriorOnlyWarning(SelectionWarning):
    """No correction beat the prior alone on held-out forecasts: the fit returned the prior
    alone (``model.prior_only_`` is True)."""


class ExtrapolationWarning(UserWarning):
    """A fitted model was evaluated outside the region of states and inputs its terms were
    fitted on (``model.region_``); the message names the variables and how far."""


def describe(value) -> str:
    """Short description of a value for error messages: type and shape, never its content."""
    shape = getattr(value, "shape", None)
    if shape is not None:
        return f"{type(value).__name__} of shape {tuple(shape)}"
    if isinstance(value, (list, tuple)):
        return f"{type(value).__name__} of length {len(value)}"
    return repr(value) if isinstance(value, (int, float, str, type(None))) else type(value).__name__


def short_repr(text, limit: int = 80) -> str:
    """``repr(text)`` for messages, cut to ``limit`` characters."""
    shown = repr(text)
    return shown if len(shown) <= limit else shown[:limit - 3] + "..."


class IllConditionedWarning(UserWarning):
    """The terms a fit kept are nearly collinear on the data (the condition number of their
    column-scaled Gram matrix is above 1e10): their coefficients, solved from the Gram
    statistics, are determined only to about ``condition × 1e-16`` relative, and any split
    between the named terms is arbitrary. The message names the terms and the number."""
