"""What the MPC campaign test modules share: the controllers they compare, and an experiment
run in its quick mode with its results."""
import json

from discrepancy_paper.experiments import get_experiment

CONTROLLERS = ["flawed + TVLQR", "hybrid + TVLQR", "hybrid + MPC",
               "hybrid + MPC + re-identification"]


def quick_run(name, tmp_path_factory):
    """Run experiment ``name`` (quick mode) into a fresh folder: its folder and results."""
    out = get_experiment(name)(tmp_path_factory.mktemp(name), quick=True)
    return out, json.loads((out / "results.json").read_text())
