"""The ROS 2 node's parameters: one schema for the node's own values and the planner's options.

Source: docs/design.md §8 (topics, mounts, ``use_sim_time``) and the planner's option schema
(:mod:`viapath.ros2.options`). Every parameter is an :class:`~viapath.ros2.options.Option`; the
node declares them with their unit and bounds in the description, and :func:`validate` refuses a
bad value with one message naming the parameter (the node then does not drive).

What we chose:
* The planner's options (:mod:`viapath.options`) live under ``planner.`` with their dotted path
  (``planner.horizon_s``, ``planner.weights.k1``); which planner under ``planner_name``.
* The shield (:mod:`viapath.safety`) is ``use_shield`` (default: as ``viapath run``, on for
  ``viapath``) with its options under ``shield.`` (``shield.mode``, ``shield.margin_m``).
* Scanners are a list of names (``scanner_names``) with ``scanners.<name>.topic``, ``.frame_id``,
  ``.mount_x_m``, ``.mount_y_m``, ``.mount_yaw_rad``. The defaults are the paper's pair (URG-04LX
  0.145 m ahead facing forward, 0.145 m behind facing backward).
* ``scan_geometry``: ``urg04lx`` checks every scan against the URG-04LX beam layout (683 beams,
  0.352°) and refuses one that differs; ``from_message`` takes the beam layout of the first scan
  of each scanner (a bag from another scanner, ``viapath ros2 play``) and refuses later scans that
  differ from it.
* A ROS parameters file (``node: {ros__parameters: {...}}``, nested maps or dotted keys) is read
  here too, so that an unknown name is an error (rclpy would ignore it silently).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from viapath.limits import LIMITS_OPTIONS, ROBOT_OPTIONS, SUBGOAL_OPTIONS
from viapath.perception.detection import RETIRED_LASER_OPTIONS
from viapath.perception.scanner import URG04LX_MOUNT_OFFSET_M
from viapath.perception.tracking import TrackerParams
from viapath.ros2.options import Option, planner_options

_TRACKER = TrackerParams()  # the tracker's defaults, the simulator's and the node's


def _opt(name: str, default, unit: str = "", minimum=None, maximum=None, help: str = "", choices=None) -> Option:
    """A node option (keywords: :class:`viapath.options.Option` takes ``help`` third)."""
    return Option(name=name, default=default, help=help, unit=unit, minimum=minimum, maximum=maximum, choices=choices)


NODE_NAME = "viapath"
PLANNER_PREFIX = "planner."
SHIELD_PREFIX = "shield."
WEIGHTS_PRESET = "weights_preset"  # one parameter selects a preset (viapath.presets); planner.* stays the schema


#: The subgoal policy's options the node declares (blocked_clearance_m keeps its default there).
NODE_SUBGOAL_OPTIONS = ("reach_threshold_m", "goal_tolerance_m", "bypass_distance_m")

MAX_ROLLOUT_STEPS = 2000  # steps of one roll-out (rollout_s / rollout_dt_s, escape_s / escape_dt_s)


MAX_MOUNT_OFFSET_M = 10.0  # m: a scanner sits on the robot; a mount farther out (parameter or TF) is refused


class ParameterError(ValueError):
    """Parameter values the node refuses; the message names each parameter, one line per mistake
    (``errors`` holds the lines)."""

    def __init__(self, message: str | list[str]):
        self.errors = [message] if isinstance(message, str) else list(message)
        super().__init__("\n".join(self.errors))


def _scanner_options(name: str, topic: str, frame: str, x: float, yaw: float) -> tuple[Option, ...]:
    p = f"scanners.{name}."
    return (
        _opt(p + "topic", topic, "", help=f"sensor_msgs/LaserScan topic of the {name} scanner"),
        _opt(p + "frame_id", frame, "", help="frame_id its scans must carry ('' accepts any)"),
        _opt(
            p + "mount_x_m",
            x,
            "m",
            -MAX_MOUNT_OFFSET_M,
            MAX_MOUNT_OFFSET_M,
            "scanner position ahead of the robot centre",
        ),
        _opt(
            p + "mount_y_m",
            0.0,
            "m",
            -MAX_MOUNT_OFFSET_M,
            MAX_MOUNT_OFFSET_M,
            "scanner position left of the robot centre",
        ),
        _opt(p + "mount_yaw_rad", yaw, "rad", -math.pi, math.pi, "scanner axis relative to the robot heading"),
    )


NODE_OPTIONS: tuple[Option, ...] = (
    (
        _opt("scanner_names", ["front", "rear"], "", help="names of the scanners (each has scanners.<name>.*)"),
        _opt(
            "scan_geometry", "urg04lx", "", help="beam layout the scans must have", choices=("urg04lx", "from_message")
        ),
        _opt("odom_topic", "odom", "", help="nav_msgs/Odometry topic"),
        _opt("path_topic", "designated_path", "", help="nav_msgs/Path topic of the designated path (transient local)"),
        _opt(
            "path_file",
            "",
            "",
            help="designated path from a file instead (scenario YAML, or YAML/CSV of x y waypoints)",
        ),
        _opt(
            "map_topic",
            "",
            "",
            help="nav_msgs/OccupancyGrid topic (transient local) of a known map in the odometry "
            "frame, turned into static geometry ('' : none)",
        ),
        _opt("map_occupied_threshold", 65, "", 1, 100, "occupancy (0-100) from which a map cell is an obstacle"),
        _opt(
            "static_layer",
            True,
            "",
            help="every scan return no person track explains is static geometry "
            "(planner, guard and shield keep clear of it)",
        ),
        _opt("cmd_vel_topic", "cmd_vel", "", help="command topic"),
        _opt("cmd_vel_stamped", False, "", help="publish geometry_msgs/TwistStamped instead of Twist"),
        _opt("markers_topic", "viapath/markers", "", help="visualization_msgs/MarkerArray topic"),
        _opt("status_topic", "viapath/status", "", help="diagnostic_msgs/DiagnosticArray topic"),
        _opt(
            "diagnostics_topic",
            "/diagnostics",
            "",
            help="the same statuses for robot monitors, once a second and at once when the way's state changes "
            "('' : none)",
        ),
        _opt("odom_frame", "odom", "", help="world frame of odometry and path ('' accepts any)"),
        _opt("base_frame", "base_link", "", help="robot frame (markers of the robot)"),
        _opt("half_width_m", 1.0, "m", 0.01, 100.0, "corridor half-width around the designated path"),
        _opt("half_widths_m", [0.0], "m", 0.0, 100.0, "one half-width per path segment (0 or empty: half_width_m)"),
        *ROBOT_OPTIONS,
        *LIMITS_OPTIONS,
        *(option for option in SUBGOAL_OPTIONS if option.name in NODE_SUBGOAL_OPTIONS),
        _opt(
            "scan_timeout_s", 0.3, "s", 0.05, 10.0, "a scanner silent this long is blind; all silent: brake to a stop"
        ),
        _opt("odom_timeout_s", 0.5, "s", 0.05, 10.0, "no odometry this long: brake to a stop"),
        _opt(
            "odom_speed_tolerance_mps",
            0.1,
            "m/s",
            0.0,
            1.0,
            "odometry speed beyond max_speed_mps, or above every "
            "speed commanded in the last odom_timeout_s, by more than this is a fault: brake",
        ),
        _opt(
            "odom_turn_tolerance_radps",
            0.3,
            "rad/s",
            0.0,
            5.0,
            "odometry turn rate beyond max_turn_rate_radps, or "
            "outside the turn rates commanded in the last odom_timeout_s, by more than this is a fault: brake",
        ),
        _opt(
            "odom_pose_tolerance_m",
            0.05,
            "m",
            0.001,
            1.0,
            "odometry pose change off what its twist explains by more "
            "than this (plus the acceleration limits' share) is a fault: brake",
        ),
        _opt(
            "odom_heading_tolerance_rad",
            0.1,
            "rad",
            0.001,
            1.0,
            "odometry heading change off what its turn rate "
            "explains by more than this (plus the acceleration limits' share) is a fault: brake",
        ),
        _opt(
            "wall_timeout_s",
            0.5,
            "s",
            0.05,
            10.0,
            "no input and no move of the node's clock (/clock with "
            "use_sim_time) for this long on the wall clock: brake to a stop",
        ),
        _opt("cycle_period_s", 0.1, "s", 0.01, 1.0, "scan period; also the watchdog period"),
        _opt(
            "max_invalid_fraction", 0.5, "", 0.0, 1.0, "a scan with more NaN/zero readings than this counts as failed"
        ),
        _opt("detector", "people", "", help="detector preset", choices=("people", "legs")),
        _opt(
            "tracker_acceleration_sigma_mps2",
            _TRACKER.acceleration_sigma_mps2,
            "m/s^2",
            0.01,
            10.0,
            "process noise of the tracker (real walkers: 0.5)",
        ),
        _opt(
            "tracker_static_after_s",
            _TRACKER.static_after_s,
            "s",
            0.0,
            3600.0,
            "a track standing still this long is static geometry, not a person (0: never)",
        ),
        _opt("blind_person_speed_mps", 1.0, "m/s", 0.0, 5.0, "walking speed assumed for someone in a blind sector"),
        _opt(
            "blind_clearance_m", 0.3, "m", 0.0, 10.0, "distance from the body an unseen person is assumed to start from"
        ),
        _opt(
            "reset_hold_s",
            0.5,
            "s",
            0.0,
            10.0,
            "after a time jump backwards the robot stands this long (tracks re-confirm)",
        ),
        _opt("autostart", True, "", help="configure and activate the lifecycle node at start"),
        _opt(
            "executor",
            "events",
            "",
            help="rclpy executor: events (rclpy's EventsExecutor, callbacks dispatched "
            "from C++: lower latency) or single-threaded (rclpy's pure-Python SingleThreadedExecutor)",
            choices=("events", "single-threaded"),
        ),
        _opt(
            "interface",
            "topics",
            "",
            help="topics: the designated path comes on path_topic; nav2: as Nav2's controller "
            "server, paths come as FollowPath goals (docs/nav2.md)",
            choices=("topics", "nav2"),
        ),
        _opt(
            "use_tf",
            True,
            "",
            help="nav2: take the path frame's transform to odom_frame and the scanner mounts from /tf and "
            "/tf_static (the scanners.* mounts stay the fallback)",
        ),
        _opt("follow_path_action", "follow_path", "", help="nav2: name of the nav2_msgs/FollowPath action served"),
        _opt("speed_limit_topic", "speed_limit", "", help="nav2: nav2_msgs/SpeedLimit topic honoured"),
        _opt(
            "clear_costmap_service",
            "local_costmap/clear_entirely_local_costmap",
            "",
            help="nav2: the costmap-clearing "
            "service Nav2's behaviour tree calls on the controller's costmap (answered; there is no costmap)",
        ),
        _opt(
            "progress_radius_m", 0.5, "m", 0.01, 100.0, "nav2: the robot must move this far within progress_patience_s"
        ),
        _opt(
            "progress_patience_s",
            10.0,
            "s",
            0.1,
            3600.0,
            "nav2: no progress this long ends the goal (FAILED_TO_MAKE_PROGRESS)",
        ),
        _opt(
            "failure_tolerance_s",
            2.0,
            "s",
            0.0,
            3600.0,
            "nav2: no command can be computed this long (inputs stale, path "
            "frame unknown) ends the goal (NO_VALID_CONTROL)",
        ),
        _opt(
            "path_simplify_m", 0.05, "m", 0.0, 10.0, "nav2: a goal's dense path is simplified to subgoals within this"
        ),
        _opt(
            "use_shield",
            "default",
            "",
            help="passive-safety shield around the planner (docs/design.md §7); default: as viapath run (on for viapath)",
            choices=("default", "on", "off"),
        ),
    )
    + _scanner_options("front", "scan_front", "laser_front", URG04LX_MOUNT_OFFSET_M, 0.0)
    + _scanner_options("rear", "scan_rear", "laser_rear", -URG04LX_MOUNT_OFFSET_M, math.pi)
)


def _under(prefix: str, options: Iterable[Option]) -> list[Option]:
    """``options`` as ROS parameters named ``prefix`` + their dotted path, with the same default, bounds and help."""
    return [
        Option(
            name=prefix + o.path,
            default=o.default,
            help=o.help,
            unit=o.unit,
            minimum=o.minimum,
            maximum=o.maximum,
            exclusive_minimum=o.exclusive_minimum,
            choices=o.choices,
            former_names=tuple(
                prefix + o.path.rpartition(".")[0] + ("." if "." in o.path else "") + f for f in o.former_names
            ),
        )
        for o in options
    ]


def all_options(planner_name: str = "viapath", scanner_names=("front", "rear")) -> tuple[Option, ...]:
    """Every parameter of the node: its own, one block per scanner, and ``planner.*`` from the schema."""
    own = [o for o in NODE_OPTIONS if not o.name.startswith("scanners.")]
    by_name = {o.name: o for o in NODE_OPTIONS}
    scanners = []
    for name in scanner_names:
        for o in _scanner_options(name, f"scan_{name}", f"laser_{name}", 0.0, 0.0):
            scanners.append(by_name.get(o.name, o))
    planner = _under(PLANNER_PREFIX, planner_options(planner_name))
    from viapath.safety import SHIELD_OPTIONS

    shield = _under(SHIELD_PREFIX, [o for o in SHIELD_OPTIONS if o.name != "enabled"])  # on / off is use_shield
    preset = (
        [
            _opt(
                WEIGHTS_PRESET,
                "",
                help="weights preset name or preset YAML file (viapath presets); "
                "a planner.weights.* parameter set to other than its default wins over it",
            )
        ]
        if planner_name == "viapath"
        else []
    )
    return tuple(
        own
        + [_opt("planner_name", planner_name, help="registered planner (viapath planners)")]
        + scanners
        + preset
        + planner
        + shield
    )


def describe(option: Option) -> str:
    """A parameter description with its unit and bounds, as ``ros2 param describe`` shows it."""
    parts = [option.help] if option.help else []
    if option.unit:
        parts.append(f"unit: {option.unit}")
    if option.minimum is not None or option.maximum is not None:
        low = "-inf" if option.minimum is None else f"{option.minimum:g}"
        high = "inf" if option.maximum is None else f"{option.maximum:g}"
        parts.append(f"range: {'(' if getattr(option, 'exclusive_minimum', False) else '['}{low}, {high}]")
    choices = getattr(option, "choices", None)
    if choices:
        parts.append("one of: " + ", ".join(choices))
    return "; ".join(parts)


def _check_number(option: Option, value, where: str):
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ParameterError(f"{where}: expected a number, found {value!r}")
    if not math.isfinite(float(value)):
        raise ParameterError(f"{where}: expected a finite number, found {value}")
    if option.minimum is not None and getattr(option, "exclusive_minimum", False) and value <= option.minimum:
        raise ParameterError(f"{where}: expected > {option.minimum:g} {option.unit}".rstrip() + f", found {value}")
    if option.minimum is not None and value < option.minimum:
        raise ParameterError(f"{where}: expected >= {option.minimum:g} {option.unit}".rstrip() + f", found {value}")
    if option.maximum is not None and value > option.maximum:
        raise ParameterError(f"{where}: expected <= {option.maximum:g} {option.unit}".rstrip() + f", found {value}")
    return type(option.default)(value) if isinstance(option.default, (int, float)) else value


def check_value(option: Option, value):
    """The value converted to the option's type, or :class:`ParameterError` naming the parameter."""
    where = f"parameter {option.name}"
    default = option.default
    if isinstance(default, bool):
        if not isinstance(value, bool):
            raise ParameterError(f"{where}: expected true or false, found {value!r}")
        return value
    if isinstance(default, str):
        if not isinstance(value, str):
            raise ParameterError(f"{where}: expected a string, found {value!r}")
        choices = getattr(option, "choices", None)
        if choices and value not in choices:
            raise ParameterError(f"{where}: expected one of {', '.join(choices)}, found {value!r}")
        return value
    if isinstance(default, (list, tuple)):
        if not isinstance(value, (list, tuple, np.ndarray)):
            raise ParameterError(f"{where}: expected a list, found {value!r}")
        if default and isinstance(default[0], str):
            if not all(isinstance(v, str) and v for v in value) or not len(value):
                raise ParameterError(f"{where}: expected a non-empty list of names, found {list(value)!r}")
            return list(value)
        out = [float(_check_number(option, v, f"{where}[{i}]")) for i, v in enumerate(value)]
        return out
    if isinstance(default, int) and isinstance(value, float) and not value.is_integer():
        raise ParameterError(f"{where}: expected an integer, found {value}")
    value = _check_number(option, value, where)
    return int(value) if isinstance(default, int) else float(value)


@dataclass(frozen=True)
class ScannerSetting:
    name: str
    topic: str
    frame_id: str
    mount_x_m: float
    mount_y_m: float
    mount_yaw_rad: float


@dataclass(frozen=True)
class NodeSettings:
    """Validated parameter values (``values``), with the scanners and planner options pulled out."""

    values: dict[str, Any]
    scanners: tuple[ScannerSetting, ...]
    planner_name: str
    planner_values: dict[str, Any] = field(default_factory=dict)
    shield_values: dict[str, Any] = field(default_factory=dict)

    @property
    def shield_flag(self) -> bool | None:
        """For :func:`viapath.safety.shielded`: None = the planner's default."""
        return {"default": None, "on": True, "off": False}[self.values["use_shield"]]

    def __getattr__(self, name: str):
        try:
            return self.__dict__["values"][name]
        except KeyError:
            raise AttributeError(name) from None


def _without_retired_options(values: dict[str, Any], planner_name: str) -> dict[str, Any]:
    """``values`` without the retired names of the laser chain (``fit_compute``), the planner (``planner.compute``)
    and the shield (``shield.compute``): read and ignored, with a FutureWarning saying why, as in a scenario file."""
    from viapath.planning import planner_class
    from viapath.safety import SHIELD_OPTIONS

    where: dict[str, Any] = {"where": "ROS 2 parameter", "separator": " ", "stacklevel": 3}
    values = RETIRED_LASER_OPTIONS.drop(values, **where)
    values = planner_class(planner_name).options.retired.drop(values, prefix=PLANNER_PREFIX, **where)
    return SHIELD_OPTIONS.retired.drop(values, prefix=SHIELD_PREFIX, **where)


def validate(values: dict[str, Any]) -> NodeSettings:
    """Check every value against its option; unknown names and bad values raise :class:`ParameterError`."""
    planner_name = _planner_name(values)
    names_option = next(o for o in NODE_OPTIONS if o.name == "scanner_names")
    scanner_names = check_value(names_option, values.get("scanner_names", names_option.default))
    if len(set(scanner_names)) != len(scanner_names):
        raise ParameterError(f"parameter scanner_names: names repeat: {scanner_names}")
    options = {o.name: o for o in all_options(planner_name, scanner_names)}
    values = _without_retired_options(values, planner_name)
    renamed = {f: o.name for o in options.values() for f in o.former_names}
    errors = [
        f"parameter {name}: unknown parameter" + (f" (now called {renamed[name]})" if name in renamed else "")
        for name in sorted(set(values) - set(options) - {"use_sim_time"})
    ]
    checked: dict[str, Any] = {}
    bad: set[str] = set()
    for name, o in options.items():
        try:
            checked[name] = check_value(o, values.get(name, o.default))
        except ParameterError as error:  # go on with the default, to report every mistake at once
            errors.append(str(error))
            checked[name], bad = o.default, bad | {name}
    scanners = tuple(
        ScannerSetting(
            n,
            checked[f"scanners.{n}.topic"],
            checked[f"scanners.{n}.frame_id"],
            checked[f"scanners.{n}.mount_x_m"],
            checked[f"scanners.{n}.mount_y_m"],
            checked[f"scanners.{n}.mount_yaw_rad"],
        )
        for n in scanner_names
    )
    for s in scanners:
        if not s.topic:
            errors.append(f"parameter scanners.{s.name}.topic: expected a topic name, found ''")
    if checked["nominal_speed_mps"] > checked["max_speed_mps"] and not {"nominal_speed_mps", "max_speed_mps"} & bad:
        errors.append(
            f"parameter nominal_speed_mps: expected <= max_speed_mps ({checked['max_speed_mps']:g} m/s), "
            f"found {checked['nominal_speed_mps']}"
        )
    planner_values = {k[len(PLANNER_PREFIX) :]: v for k, v in checked.items() if k.startswith(PLANNER_PREFIX)}
    errors += _apply_preset(checked, options, planner_values, planner_name)
    errors += _planner_errors(planner_name, planner_values, bad, errors)
    if errors:
        raise ParameterError(errors)
    shield_values = {k[len(SHIELD_PREFIX) :]: v for k, v in checked.items() if k.startswith(SHIELD_PREFIX)}
    return NodeSettings(checked, scanners, planner_name, planner_values, shield_values)


def _planner_name(values: dict[str, Any]) -> str:
    planner_name = values.get("planner_name", "viapath")
    if not isinstance(planner_name, str):
        raise ParameterError(f"parameter planner_name: expected a string, found {planner_name!r}")
    from viapath.planning import available_planners

    if planner_name not in available_planners():
        raise ParameterError(
            f"parameter planner_name: unknown planner {planner_name!r}; available: {', '.join(available_planners())}"
        )
    return planner_name


def _apply_preset(checked: dict, options: dict, planner_values: dict, planner_name: str) -> list[str]:
    """Put the ``weights_preset``'s values into ``checked`` and ``planner_values`` (in place); its errors."""
    if not checked.get(WEIGHTS_PRESET):
        return []
    from viapath.presets import PresetError, load_preset

    try:
        preset = load_preset(checked[WEIGHTS_PRESET])
    except PresetError as error:
        return [f"parameter {WEIGHTS_PRESET}: {error}"]
    if preset.planner != planner_name:
        return [
            f"parameter {WEIGHTS_PRESET}: preset {preset.name!r} is for planner "
            f"{preset.planner!r}, not {planner_name!r}"
        ]
    # A parameter set to other than its default wins over the preset. (The node declares every
    # parameter and hands all values over, so "given" can only be told apart from "default" by value.)
    for path, value in preset.dotted().items():
        name = PLANNER_PREFIX + path
        if checked[name] == options[name].default:
            planner_values[path] = value
            checked[name] = value
    return []


def _planner_errors(planner_name: str, planner_values: dict, bad: set, earlier: list[str]) -> list[str]:
    """Roll-outs too long for their step, then what the planner's own schema refuses (not said before)."""
    errors: list[str] = []
    for length, step in (("rollout_s", "rollout_dt_s"), ("escape_s", "escape_dt_s")):
        if (
            length in planner_values
            and step in planner_values
            and not {PLANNER_PREFIX + length, PLANNER_PREFIX + step} & bad
        ):
            steps = planner_values[length] / planner_values[step]
            if steps > MAX_ROLLOUT_STEPS:  # both named: either may be the one to change
                for name in (length, step):
                    errors.append(
                        f"parameter {PLANNER_PREFIX}{name}: {length} {planner_values[length]:g} s / {step} "
                        f"{planner_values[step]:g} s is {steps:.4g} steps of a roll-out, at most {MAX_ROLLOUT_STEPS}"
                    )
    from viapath.options import OptionError
    from viapath.planning import planner_class

    try:  # the planner's own schema has the last word (e.g. checks across options)
        planner_class(planner_name).options.validate(planner_values)
    except OptionError as error:
        for where, message in error.errors or [("", str(error))]:
            line = f"parameter {PLANNER_PREFIX}{where}: {message}"
            if line not in earlier and line not in errors and PLANNER_PREFIX + where not in bad:
                errors.append(line)
    return errors


def _flatten(data: dict, prefix: str = "") -> dict[str, Any]:
    out = {}
    for key, value in data.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            out.update(_flatten(value, name + "."))
        else:
            out[name] = value
    return out


def read_params_file(path, node_name: str = NODE_NAME) -> dict[str, Any]:
    """The node's values from a ROS 2 parameters file (``/**`` and ``node_name`` sections merged)."""
    from viapath.io.safe_read import InputError, read_yaml_file

    path = Path(path)
    if not path.exists():
        raise ParameterError(f"{path}: no such parameters file")

    try:
        data = read_yaml_file(path, "parameters file") or {}
    except InputError as error:
        raise ParameterError(str(error)) from None
    if not isinstance(data, dict):
        raise ParameterError(f"{path}: expected a map of node names to {{ros__parameters: ...}}")
    values: dict[str, Any] = {}
    found = False
    for key in ("/**", node_name, "/" + node_name):
        section = data.get(key)
        if section is None:
            continue
        if not isinstance(section, dict) or not isinstance(section.get("ros__parameters"), dict):
            raise ParameterError(f"{path}: {key}: expected a map with 'ros__parameters'")
        values.update(_flatten(section["ros__parameters"]))
        found = True
    if not found:
        raise ParameterError(f"{path}: no section for node {node_name!r} (or '/**') with ros__parameters")
    return values


def write_example_params(path, planner_name: str = "viapath") -> None:
    """A parameters file holding every parameter at its default, with units and bounds as comments."""
    lines = [
        f"# viapath ROS 2 node parameters (defaults). Run: viapath ros2 node --params-file {Path(path).name}",
        f"{NODE_NAME}:",
        "  ros__parameters:",
    ]
    for o in all_options(planner_name):
        value = o.default
        text = (
            ("true" if value else "false")
            if isinstance(value, bool)
            else repr(value)
            if isinstance(value, str)
            else (
                "[" + ", ".join(repr(v) if isinstance(v, str) else repr(float(v)) for v in value) + "]"
                if isinstance(value, (list, tuple))
                else repr(float(value))
                if isinstance(value, float)
                else str(value)
            )
        )
        text = text.replace("'", '"')
        lines.append(f"    {o.name}: {text}  # {describe(o)}")
    Path(path).write_text("\n".join(lines) + "\n")
