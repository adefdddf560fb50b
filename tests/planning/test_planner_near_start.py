"""An obstacle already inside the planner's safety margin that sweeps past the robot.

Found by the random safety test with starts closer than the margin: the escape fan used to judge
overlapped obstacles only by where they would be after 1 s, so standing still won and was labelled
'stop' although the sweep hits a standing robot at t = 0.44 s while sideways motions miss it.
"""

import numpy as np

from tests.planning import test_planner_safety as safety
from viapath.observation import MotionLimits, Observation, Obstacles, RobotState
from viapath.path import DesignatedPath


def test_stop_only_when_standing_still_is_safe():
    path = DesignatedPath([[0.0, 0.0], [2.0, 0.0]], half_width_m=0.4)
    robot = RobotState(np.array([0.0, 0.0]), 0.0, 0.0, radius_m=0.25)
    obstacles = Obstacles(np.array([[-0.22107801, 0.48306426]]), np.array([[0.5, 0.0]]), np.array([0.25]))
    safety.check_plan_against_status(
        (path, Observation(0.0, robot, obstacles), 0.5, MotionLimits(max_speed_mps=0.5, max_turn_rate_radps=1.0))
    )
