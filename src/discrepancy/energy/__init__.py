"""Energy discrepancy: the energy a conservative model misses, learned as sparse friction laws."""
from .dissipation import (
    FrictionTerm,
    default_friction_library,
    integrated_powers,
    support_loss_terms,
    without_stribeck,
)
from .dissipation_model import DissipationDiscrepancy
from .hamiltonian import EnergyTautologyWarning, check_span, energy_span_residual
from .metrics import error_summary, percent_error
from .protocol import BlindFit, blind_fit, default_procedures
from .record import PreparedRecording
from .smoothing import choose_smoothing
from .soundness import holding_torques, turning_points
from .state_form import EnergyDiscrepancy
from .subsets import DissipationFit, fit_dissipation, select_terms
from .uncertainty import DissipationUncertainty

__all__ = ["BlindFit", "DissipationDiscrepancy", "DissipationFit", "DissipationUncertainty",
           "EnergyDiscrepancy", "EnergyTautologyWarning", "FrictionTerm", "PreparedRecording",
           "blind_fit", "check_span", "choose_smoothing", "default_friction_library",
           "default_procedures", "energy_span_residual", "error_summary", "fit_dissipation",
           "holding_torques", "integrated_powers", "percent_error", "select_terms",
           "support_loss_terms", "turning_points", "without_stribeck"]
