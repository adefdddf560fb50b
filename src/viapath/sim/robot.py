"""The simulated robot moves exactly as the core kinematic model says (``viapath.kinematics``)."""

from viapath.kinematics import UnicycleState, limit_command, step

__all__ = ["UnicycleState", "limit_command", "step"]
