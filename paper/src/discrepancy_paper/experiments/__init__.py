"""Paper examples: each writes figures, ``report.md`` and ``results.json`` to ``DIR/NAME/``.

Every entry maps an experiment name to ``(module, function)``; the function has the
signature ``run(out_dir, *, quick=False) -> pathlib.Path`` (the folder it wrote).
``quick=True`` runs a reduced version (fewer seeds) for tests.
"""
from importlib import import_module

EXPERIMENTS = {
    "vdp-parameter": ("van_der_pol", "run_parameter"),
    "vdp-structure": ("van_der_pol", "run_structure"),
    "pendulum-energy": ("pendulum_energy", "run_synthetic"),
    "pendulum-energy-experiment": ("pendulum_energy", "run_experiment"),
    "energy-systems": ("energy_systems", "run"),
    "cart-swingup": ("cart_swingup", "run"),
    "cart-mpc": ("cart_mpc", "run"),
    "cart-leaderboard": ("cart_leaderboard", "run"),
    "pendulum-cart-mpc": ("pendulum_cart_mpc", "run"),
    "noise-study": ("noise_study", "run"),
    "silverbox": ("silverbox", "run"),
    "cascaded-tanks": ("cascaded_tanks", "run"),
    "prediction-error": ("prediction_error", "run"),
    "blind-selection": ("blind_selection", "run"),
    "pde-burgers": ("pde_examples", "run_burgers"),
    "pde-reaction-diffusion": ("pde_examples", "run_reaction_diffusion"),
    "pde-kuramoto-sivashinsky": ("pde_examples", "run_kuramoto_sivashinsky"),
}


def get_experiment(name: str):
    """The ``run`` function of experiment ``name``."""
    from discrepancy.errors import UnknownNameError

    if name not in EXPERIMENTS:
        raise UnknownNameError(f"experiment {name!r} is not known; valid names: "
                               f"{', '.join(EXPERIMENTS)}")
    module, function = EXPERIMENTS[name]
    return getattr(import_module(f".{module}", __name__), function)
