"""viapath as an IR-SIM behaviour: ``behavior: {name: viapath, ...}`` on a ``diff`` robot (extra ``irsim``).

Source: IR-SIM (R. Han et al., https://github.com/hanruihua/ir-sim, PyPI ``ir-sim``) registers its own
behaviours (``rvo``, ``dash``, ``sfm``) with ``register_behavior(kinematics, name)``, and stateful ones
with ``register_behavior_class``: a class built once per object with the world file's ``behavior``
block as keyword arguments, then called every step with the robot (``ego_object``) and the objects
around it (``external_objects``), returning ``[[v], [ω]]`` for a ``diff`` robot. This module registers
``viapath`` both ways on import.

How it is loaded: IR-SIM reads no entry points and its world file names no module, so the user's
script names this one, in IR-SIM's own way for behaviours of other packages::

    env = irsim.make("world.yaml")
    env.load_behavior("viapath.integrations.irsim")   # or: import viapath.integrations.irsim first

What the behaviour reads each step, and the choices made:
* Options: the ``behavior`` block less IR-SIM's own keys (``name``, ``target_roles``), checked against
  :func:`viapath.integrations.host.behaviour_options` with :data:`IRSIM_OPTIONS` (an unknown or
  out-of-range option is refused naming the field: at load in IR-SIM's log, and as an
  :class:`~viapath.options.OptionError` on the first step).
* The robot: pose, ``[v, ω]``, circle radius (another shape: its circumscribed radius,
  ``radius_extend``); limits from ``vel_max`` and ``acce`` (unbounded ones: see
  :mod:`~viapath.integrations.host`); the path from ``path`` or the robot's start and goal(s).
* ``sensing: objects`` (default): objects that move (``static: false``) are people, as discs at their
  centroid with their velocity (circles with their radius, other shapes with the circumscribed one);
  static polygons, rectangles, lines, circles and grid maps are viapath's static layer, none dropped.
  Objects IR-SIM does not collide with (``unobstructed``) are left out.
* ``sensing: lidar``: the robot's first ``lidar2d`` scan through viapath's laser chain
  (:class:`~viapath.perception.LaserPerception`: detection, tracking, and every return no person
  explains as static geometry), with a scanner model of IR-SIM's beam count, field of view, range and
  mounting offset. Returns at the lidar's ``range_max`` are "no return".
* A world reset (the simulated time going back) starts the planner and the tracks anew.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

try:
    from irsim.lib import register_behavior, register_behavior_class
except ImportError as error:  # pragma: no cover - depends on the extra
    raise ImportError("viapath's IR-SIM behaviour needs IR-SIM: pip install 'viapath[irsim]'") from error

from viapath.integrations.host import (
    Driver,
    behaviour_options,
    bounded_limits,
    read_options,
    read_waypoints,
    static_layer,
)
from viapath.limits import ROBOT_OPTIONS
from viapath.observation import Observation, Obstacles, RobotState
from viapath.options import Option, OptionError, OptionSet, Settings
from viapath.perception import LaserPerception, ScannerModel
from viapath.static import StaticLayer

NAME = "viapath"
KINEMATICS = "diff"
IRSIM_KEYS = ("name", "target_roles")  # IR-SIM's own keys of a behavior block

IRSIM_OPTIONS = OptionSet(
    [
        ROBOT_OPTIONS["nominal_speed_mps"],
        Option(
            "sensing",
            "objects",
            "objects: IR-SIM's objects as given (moving ones are people, static ones the static layer); "
            "lidar: the robot's lidar2d scans through viapath's laser chain",
            choices=("objects", "lidar"),
        ),
    ],
    owner="irsim behavior viapath",
)

SCHEMA = behaviour_options(IRSIM_OPTIONS)


def read_behavior(block: dict[str, Any]) -> tuple[Settings, np.ndarray | None]:
    """The options of a ``behavior: {name: viapath, ...}`` block and its ``path`` (None: from the goal)."""
    values = {k: v for k, v in block.items() if k not in IRSIM_KEYS}
    path = values.pop("path", None)
    return read_options(SCHEMA, values, where="behavior"), read_waypoints(path, "behavior.path")


def _column(value: Any) -> np.ndarray:
    return np.asarray(value, dtype=float).reshape(-1)


def robot_state(ego: Any) -> RobotState:
    state, velocity = _column(ego.state), _column(ego.velocity)
    return RobotState(
        position=state[:2].copy(),
        heading_rad=float(state[2]),
        speed_mps=float(velocity[0]),
        turn_rate_radps=float(velocity[1]),
        radius_m=_radius(ego),
    )


def _radius(obj: Any) -> float:
    return float(obj.radius) if obj.shape == "circle" else float(obj.radius_extend)


def _is_static(obj: Any) -> bool:
    return obj.shape == "map" or bool(obj.static)


def _obstructing(external_objects: list[Any]) -> list[Any]:
    return [obj for obj in external_objects if not getattr(obj, "unobstructed", False)]


def people_of(external_objects: list[Any]) -> Obstacles:
    """The objects that move, as people: discs at their centroid with the velocity IR-SIM gives them."""
    people = [
        (_column(obj.centroid)[:2], _column(obj.velocity_xy)[:2], _radius(obj), int(obj.id))
        for obj in _obstructing(external_objects)
        if not _is_static(obj)
    ]
    if not people:
        return Obstacles.empty()
    positions, velocities, radii, ids = (np.array(column) for column in zip(*people))
    return Obstacles(positions, velocities, radii.astype(float), ids=ids)


def _map_segments(obj: Any) -> np.ndarray:
    """A grid map's outline (IR-SIM keeps it as line strings) as segments (M, 2, 2)."""
    pieces = [np.asarray(line.coords, dtype=float) for line in obj.linestrings]
    return np.concatenate([np.stack([p[:-1], p[1:]], axis=1) for p in pieces if len(p) > 1] or [np.zeros((0, 2, 2))])


def static_of(external_objects: list[Any]) -> StaticLayer:
    """The static objects as viapath's static layer: polygons, rectangles, lines, circles and grid maps."""
    polygons, polylines, circles, maps = [], [], [], []
    for obj in _obstructing(external_objects):
        if obj.shape == "map":
            maps.append(_map_segments(obj))
        elif not obj.static:
            continue
        elif obj.shape == "circle":
            circles.append((_column(obj.centroid)[:2], float(obj.radius)))
        elif obj.shape == "linestring":
            polylines.append(np.asarray(obj.vertices, dtype=float).T)
        else:  # polygon, rectangle and any other closed outline
            polygons.append(np.asarray(obj.vertices, dtype=float).T)
    return static_layer(polygons, polylines, circles, maps)


def _lidar(ego: Any) -> Any:
    for sensor in getattr(ego, "sensors", []) or []:
        if getattr(sensor, "sensor_type", "") == "lidar2d":
            return sensor
    return None


def scanner_model(lidar: Any) -> ScannerModel:
    """viapath's model of an IR-SIM ``lidar2d``: its beams, range and mounting (noise is IR-SIM's)."""
    offset = _column(lidar.offset)
    return ScannerModel(
        name="irsim-lidar",
        mount_x_m=float(offset[0]),
        mount_y_m=float(offset[1]),
        mount_yaw_rad=float(offset[2]) if len(offset) > 2 else 0.0,
        beam_count=int(lidar.number),
        angle_increment_rad=float(lidar.angle_inc),
        range_min_m=float(lidar.range_min),
        range_max_m=float(lidar.range_max),
        scan_period_s=float(lidar.scan_time),
        noise_sigma_near_m=0.0,
        noise_fraction_far=0.0,
    )


class ViapathBehavior:
    """IR-SIM's class-based behaviour ``viapath`` for ``diff`` robots (built once per robot)."""

    def __init__(self, object_info: Any = None, **block: Any) -> None:
        self.settings, self.waypoints = read_behavior(block)
        self.driver = Driver(self.settings)
        self.laser: LaserPerception | None = None
        self._last_time_s = -math.inf
        # IR-SIM never moves a static object: their layer is built once per set of them and kept, so the
        # guard's sampling of it into discs (cached on the layer) is done once, not every step.
        self._static: tuple[tuple[int, ...], StaticLayer] | None = None

    def _start(self, ego: Any) -> None:
        world = ego._world_param
        state = _column(ego.state)
        goals = [_column(goal)[:2] for goal in getattr(ego, "_goal", [])] or [_column(ego.goal)[:2]]
        waypoints = self.waypoints if self.waypoints is not None else np.array([state[:2], *goals])
        vel_max, acce = _column(ego.vel_max), _column(ego.info.acce)
        self.driver.start(
            waypoints,
            nominal_speed_mps=min(float(self.settings["nominal_speed_mps"]), float(vel_max[0])),
            limits=bounded_limits(vel_max[0], acce[0], vel_max[1], acce[1]),
            robot_radius_m=_radius(ego),
            dt_s=float(world.step_time),
            goal_tolerance_m=0.8 * float(ego.goal_threshold),
            # IR-SIM takes its goals one by one, each reached within goal_threshold: so must viapath's subgoals.
            reach_threshold_m=0.8 * float(ego.goal_threshold) if self.waypoints is None else None,
        )
        self.laser, self._static = None, None
        if self.settings["sensing"] == "lidar":
            lidar = _lidar(ego)
            if lidar is None:
                raise OptionError([("behavior.sensing", "lidar: the robot has no lidar2d sensor in the world file")])
            self.laser = LaserPerception(
                scanners=[scanner_model(lidar)], range_noise=False, robot_radius_m=_radius(ego)
            )
            self.laser.reset(np.random.default_rng(0))

    def _static_layer(self, external_objects: list[Any]) -> StaticLayer:
        key = tuple(int(obj.id) for obj in _obstructing(external_objects) if _is_static(obj))
        if self._static is None or self._static[0] != key:
            self._static = (key, static_of(external_objects))
        return self._static[1]

    def observation(self, ego: Any, external_objects: list[Any], time_s: float) -> Observation:
        robot = robot_state(ego)
        if self.laser is None:
            return Observation(time_s, robot, people_of(external_objects), self._static_layer(external_objects))
        lidar = _lidar(ego)
        scan = lidar.get_scan()
        ranges = np.asarray(scan["ranges"], dtype=float).copy()
        ranges[ranges >= float(scan["range_max"]) - 1e-6] = np.inf  # IR-SIM reports a miss as range_max
        pose = np.array([robot.position[0], robot.position[1], robot.heading_rad])
        people = self.laser.process(time_s, pose, [ranges])
        return Observation(time_s, robot, people, self.laser.last_static)

    def __call__(self, ego_object: Any, external_objects: list[Any] | None = None, **_: Any) -> np.ndarray:
        world = ego_object._world_param
        time_s = float(world.count) * float(world.step_time)
        if time_s < self._last_time_s or not self.driver.started:  # a reset world starts anew
            if ego_object.goal is None and self.waypoints is None:
                return np.zeros((2, 1))
            self._start(ego_object)
        self._last_time_s = time_s
        command = self.driver.command(self.observation(ego_object, list(external_objects or []), time_s))
        return np.array([[command.speed_mps], [command.turn_rate_radps]])


register_behavior_class(KINEMATICS, NAME)(ViapathBehavior)


@register_behavior(KINEMATICS, NAME)
def viapath_unavailable(ego_object: Any, external_objects: list[Any], **block: Any) -> np.ndarray:
    """Called by IR-SIM only when :class:`ViapathBehavior` could not be built: raises why."""
    read_behavior(block)  # an OptionError naming the field
    raise RuntimeError(f"{ego_object.name}: the viapath behaviour could not start; IR-SIM's log says why")
