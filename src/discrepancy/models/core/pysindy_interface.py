"""The names a PySINDy user reaches for on a fitted model, and scikit-learn's metadata
routing (so ``t`` reaches every fold of a search); mixed into
:class:`~discrepancy.models.discrepancy_model.DiscrepancyModel`."""
from __future__ import annotations

from .arguments import metadata_routing


class PySINDyInterface:
    """``feature_names``, ``n_features_in_``, ``n_control_features_``,
    ``n_output_features_`` (read-only) and ``get_metadata_routing``."""

    @property
    def feature_names(self) -> list[str]:
        """PySINDy's ``feature_names``: the names of the states, then the inputs."""
        return self.variable_names_

    @property
    def n_features_in_(self) -> int:
        """PySINDy's (and scikit-learn's) number of input variables: states plus inputs."""
        self.check_is_fitted()
        return self.n_states_ + self.n_inputs_

    @property
    def n_control_features_(self) -> int:
        """PySINDy's number of inputs (``n_inputs_``)."""
        self.check_is_fitted()
        return self.n_inputs_

    @property
    def n_output_features_(self) -> int:
        """PySINDy's number of library terms."""
        self.check_is_fitted()
        return self.coef_.shape[1]

    def get_metadata_routing(self):
        """scikit-learn's metadata routing: with
        ``sklearn.set_config(enable_metadata_routing=True)``, ``GridSearchCV(model,
        grid).fit(x, t=dt)`` gives every fold's ``fit`` and ``score`` its ``t`` (and ``u``,
        ``x_dot``; ``sample_weight`` to ``fit``), split like ``x``."""
        return metadata_routing(type(self).__name__)
