"""Data validation and file loading."""
from .trajectory import Trajectory, as_trajectories

__all__ = ["Trajectory", "as_trajectories"]
