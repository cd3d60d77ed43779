"""Choosing supports, libraries and procedures by forecasts, the prior alone included.

* :mod:`.choice`: the default term selection of ``DiscrepancyModel.fit``: supports
  proposed by equation error, scored by forecasts over held-out blocks of the training
  data (:class:`ForecastSelection`, in ``model.forecast_selection_``);
* :mod:`.procedures`: :func:`choose_procedure`, libraries or whole procedures chosen by
  rolling-origin forecasts inside the training data, with :func:`default_libraries`;
* :mod:`.held_out`, :mod:`.forecast`, :mod:`.candidates`: the windows kept beside the
  statistics, the batched forecasts and the candidates;
* :mod:`.output_checks`: output-error fits judged by held-out forecasts (``refine``);
  :mod:`.output_forecasts`: ``choose_procedure``'s output forecasts.
"""
from .candidate_libraries import default_libraries
from .choice import ForecastSelection
from .procedures import ProcedureChoice, choose_procedure

__all__ = ["ForecastSelection", "ProcedureChoice", "choose_procedure", "default_libraries"]
