"""Choosing supports and libraries by forecasts, the prior alone included. Below the
models: it works on a fit's set-up and statistics and knows no model class.

* :mod:`.choice`: the default term selection of ``DiscrepancyModel.fit``: supports
  proposed by equation error, scored by forecasts over held-out blocks of the training
  data (:class:`ForecastSelection`, in ``model.forecast_selection_``);
* :mod:`.forecast`, :mod:`.horizon`, :mod:`.candidates`: the batched forecasts, how far
  they reach and the candidates (the windows they start from are kept beside the
  statistics, :mod:`discrepancy.fitting.held_out`);
* :func:`default_libraries`: candidate libraries from the data and the prior, which
  :func:`discrepancy.choose_procedure` (:mod:`discrepancy.procedures`, above the models)
  compares as whole procedures; output-error fits are judged in
  :mod:`discrepancy.models.outputs.output_checks`.
"""
from .candidate_libraries import default_libraries
from .choice import ForecastSelection

__all__ = ["ForecastSelection", "default_libraries"]
