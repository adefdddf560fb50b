"""viapath: follow a designated path and avoid moving obstacles by choosing speed as well as direction.

The core (``geometry``, ``path``, ``observation``, ``planning``) is pure numpy and is what goes on a
robot; the simulator, scenarios, I/O and plotting sit around it.
"""

from viapath.observation import Command, Observation, Obstacles, RobotState
from viapath.path import DesignatedPath

__all__ = ["Command", "DesignatedPath", "Observation", "Obstacles", "RobotState"]
__version__ = "0.1.0"
