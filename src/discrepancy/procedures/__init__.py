"""Libraries and procedures chosen by forecasts inside the training data
(:func:`choose_procedure`, above the models: it fits whole models)."""
from .choose import ProcedureChoice, choose_procedure

__all__ = ["ProcedureChoice", "choose_procedure"]
