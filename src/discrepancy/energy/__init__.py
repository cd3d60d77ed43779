"""Energy discrepancy: the energy a conservative model misses, learned as sparse friction laws."""
from .dissipation import (
    DissipationFit,
    FrictionTerm,
    default_friction_library,
    fit_dissipation,
    integrated_powers,
    select_terms,
    support_loss_terms,
    without_stribeck,
)
from .dissipation_model import DissipationDiscrepancy
from .hamiltonian import EnergyTautologyWarning, check_span, energy_span_residual
from .metrics import error_summary, percent_error
from .protocol import BlindFit, blind_fit, default_procedures
from .state_form import EnergyDiscrepancy
from .uncertainty import DissipationUncertainty

__all__ = ["BlindFit", "DissipationDiscrepancy", "DissipationFit", "DissipationUncertainty",
           "EnergyDiscrepancy", "EnergyTautologyWarning", "FrictionTerm", "blind_fit",
           "check_span", "default_friction_library", "default_procedures",
           "energy_span_residual", "error_summary", "fit_dissipation", "integrated_powers",
           "percent_error", "select_terms", "support_loss_terms", "without_stribeck"]
