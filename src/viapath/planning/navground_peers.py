"""navground's behaviours as peer planners: ``nav-orca``, ``nav-hl``, ``nav-hrvo``, ``nav-sf``.

Source: the PyPI package ``navground`` (J. Guzzi et al., IDSIA; https://github.com/idsia-robotics/navground),
which implements ORCA (van den Berg et al. 2011), HL (Guzzi et al. 2013, "Human-friendly robot
navigation in dynamic environments"), HRVO (Snape et al. 2011) and a social-force behaviour. No one
here wrote them: they are real peers, driven on the same scenarios, with the same sensing and limits.

What we chose to put them behind the planner protocol:
* Kinematics: ``AheadKinematics(max_speed, max_turn_rate)``: forward speed and turn rate bounded
  independently, like our unicycle robot; acceleration limits are applied by the simulator.
* Each cycle the behaviour is given the robot pose and velocity, the tracked obstacles as
  ``Neighbor`` discs with their estimated velocities (radius grown by ``safety_margin_m`` +
  ``uncertainty_sigmas``·position σ), and the current subgoal of the shared
  :class:`~viapath.path.SubgoalTracker` as a point target at the nominal (optimal) speed.
* The corridor is given as line obstacles: both borders of the designated path, offset by the
  half-width plus the robot radius (so touching a border = the robot centre on the corridor edge),
  joined with mitred corners and closed by caps beyond both ends (without them a peer escaping a
  group turned round and left through the open start). navground has no other way to know about
  a corridor.
* The command is the behaviour's twist in the robot frame: (forward speed, angular speed); a
  negative forward speed is clipped to 0 by the robot.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from viapath.observation import Command, Decision, Plan
from viapath.options import Option, OptionSet
from viapath.path import DesignatedPath
from viapath.planning.base import COMMON_OPTIONS, Planner, Situation


def corridor_borders(waypoints: np.ndarray, half_widths: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """Segments of both corridor borders at the given offsets, with mitred joins between segments,
    closed by a straight cap the same offset beyond each end (the corridor's capsules are round there)."""
    waypoints = np.asarray(waypoints, dtype=float)
    directions = np.diff(waypoints, axis=0)
    directions /= np.hypot(*directions.T)[:, None]
    normals = np.stack([-directions[:, 1], directions[:, 0]], axis=1)  # left of travel
    segments: list[Any] = []
    ends: list[Any] = []
    for side in (1.0, -1.0):
        points = []
        n = len(directions)
        for i in range(n + 1):
            if i == 0 or i == n:
                j = 0 if i == 0 else n - 1
                beyond = -1.0 if i == 0 else 1.0
                points.append(waypoints[i] + half_widths[j] * (side * normals[j] + beyond * directions[j]))
                continue
            # Intersection of the two offset lines at the joint (mitre), bounded for sharp turns.
            a = waypoints[i] + side * half_widths[i - 1] * normals[i - 1]
            b = waypoints[i] + side * half_widths[i] * normals[i]
            matrix = np.column_stack([directions[i - 1], -directions[i]])
            if abs(np.linalg.det(matrix)) < 1e-9:
                points.append(a)
                continue
            t, _ = np.linalg.solve(matrix, b - a)
            points.append(a + np.clip(t, -3 * half_widths[i - 1], 3 * half_widths[i - 1]) * directions[i - 1])
        segments.extend(zip(points[:-1], points[1:]))
        ends.append((points[0], points[-1]))
    segments.append((ends[0][0], ends[1][0]))
    segments.append((ends[0][1], ends[1][1]))
    return segments


class _NavgroundPeer(Planner):
    behavior_type = ""
    options = COMMON_OPTIONS + OptionSet(
        [
            Option(
                "horizon_s",
                5.0,
                "navground behaviour's horizon",
                "s",
                minimum=0.0,
                exclusive_minimum=True,
                maximum=60.0,
            ),
            Option("corridor_walls", True, "give navground the corridor borders as line obstacles"),
        ],
        owner="navground",
    )

    def __init__(self, path: DesignatedPath, **kwargs: Any) -> None:
        super().__init__(path, **kwargs)
        import navground.core as core  # imported here: the extra is optional

        self._core = core
        horizon_s, corridor_walls = self.settings["horizon_s"], self.settings["corridor_walls"]
        behavior = core.Behavior.make_type(self.behavior_type)
        if behavior is None:  # pragma: no cover - depends on the navground build
            raise RuntimeError(f"navground has no behaviour {self.behavior_type!r}")
        behavior.kinematics = core.kinematics.AheadKinematics(
            self.limits.max_speed_mps, self.limits.max_turn_rate_radps
        )
        behavior.radius = self.robot_radius_m
        behavior.max_speed = self.limits.max_speed_mps
        behavior.optimal_speed = self.nominal_speed_mps
        behavior.horizon = float(horizon_s)
        behavior.safety_margin = 0.0  # the margin is added to the obstacle radii, as for every planner
        self.behavior = behavior
        self._walls = []
        if corridor_walls:
            offsets = path.half_widths_m + self.robot_radius_m
            self._walls = [core.LineSegment(a, b) for a, b in corridor_borders(path.waypoints, offsets)]
        self._dt_s = 0.1
        self._last_time_s: float | None = None

    def decide(self, situation: Situation) -> Decision:
        core = self._core
        observation, obstacles, position = situation.observation, situation.obstacles, situation.position
        robot, subgoal, index = observation.robot, situation.subgoal, situation.subgoal_index
        if self._last_time_s is not None and observation.time_s > self._last_time_s:
            self._dt_s = observation.time_s - self._last_time_s
        self._last_time_s = observation.time_s

        behavior = self.behavior
        behavior.position = position
        behavior.orientation = float(robot.heading_rad)
        behavior.velocity = robot.velocity
        behavior.angular_speed = float(robot.turn_rate_radps)
        radii = situation.inflation.obstacle_radii_m
        state: Any = behavior.environment_state  # a geometric state: neighbours, discs and lines
        people = ~obstacles.is_static
        state.neighbors = [
            core.Neighbor(p, float(r), v, int(i) % 2**31)
            for p, r, v, i in zip(  # navground's ids: int32
                obstacles.positions[people], radii[people], obstacles.velocities[people], obstacles.ids[people]
            )
        ]
        # Static geometry (walls, boxes, scan returns) as navground's static discs: they do not reciprocate.
        state.static_obstacles = [core.Disc(p, float(r)) for p, r in zip(obstacles.positions[~people], radii[~people])]
        state.line_obstacles = self._walls
        tolerance = (
            self.subgoal_policy.goal_tolerance_m if self.subgoals.is_final else self.subgoal_policy.reach_threshold_m
        )
        behavior.target = core.Target.Point(subgoal, tolerance=0.5 * tolerance)
        twist = behavior.compute_cmd(self._dt_s, core.Frame.relative)
        speed = float(twist.velocity[0])
        turn = float(twist.angular_speed)
        if not (np.isfinite(speed) and np.isfinite(turn)):
            speed, turn = 0.0, 0.0
        speed = float(np.clip(speed, 0.0, self.limits.max_speed_mps))
        heading = robot.heading_rad
        target = position + np.array([np.cos(heading), np.sin(heading)]) * max(speed, 1e-3)
        plan = Plan(self.behavior_type, speed, target, subgoal_index=index, candidate_count=len(obstacles))
        return Decision(Command(speed, turn), plan)


class NavgroundORCA(_NavgroundPeer, name="nav-orca"):
    """navground's ORCA (optimal reciprocal collision avoidance), corridor as line obstacles (extra 'navground')."""

    behavior_type = "ORCA"


class NavgroundHL(_NavgroundPeer, name="nav-hl"):
    """navground's HL (human-like, Guzzi et al. 2013), corridor as line obstacles (extra 'navground')."""

    behavior_type = "HL"


class NavgroundHRVO(_NavgroundPeer, name="nav-hrvo"):
    """navground's HRVO (hybrid reciprocal velocity obstacles), corridor as line obstacles (extra 'navground')."""

    behavior_type = "HRVO"


class NavgroundSocialForce(_NavgroundPeer, name="nav-sf"):
    """navground's SocialForce (Helbing and Molnar 1995), corridor as line obstacles (extra 'navground')."""

    behavior_type = "SocialForce"
