"""viapath as a navground behaviour: ``behavior: {type: Viapath, ...}`` (extra ``navground``).

Source: navground (J. Guzzi et al., IDSIA; https://github.com/idsia-robotics/navground, PyPI
``navground``): a Python behaviour subclasses ``navground.core.Behavior`` with ``name=`` (its
registered type) and declares its YAML options as registered properties
(``@property @register(default, description)``); the experiment runner (``navground_py run``) loads
the entry-point group ``navground_behaviors`` before it reads an experiment, so the package's entry
point ``viapath = "viapath.integrations.navground"`` makes ``Viapath`` selectable by name with no
code. In Python, ``navground.sim.load_plugins()`` (or importing this module) does the same.

Choices made where navground is silent:
* Every option of :func:`viapath.integrations.host.behaviour_options` (and :data:`NAVGROUND_OPTIONS`)
  is a property of the same name, default and description (help, unit, bounds); bounds and choices
  go into navground's JSON schema too. A value is checked by viapath's schema when set (navground
  stores floats in single precision: a value is read back at its shortest decimal), so an unknown
  or out-of-range option is refused naming the field; the combination of options once more when the
  behaviour starts.
* The robot: navground's ``optimal_speed`` is viapath's nominal speed, ``max_speed`` and the
  kinematics' ``max_angular_speed`` its limits (acceleration: options, as navground's kinematics has
  none by default), ``radius`` the robot's radius.
* The path: the ``path`` property (a list of points) or, by default, the target: a target's path
  sampled every 0.25 m, else the straight line from where the robot is when it gets a target point
  to that point (a new target point, e.g. a task's next waypoint, starts a new line).
* The environment state is a ``GeometricState`` (navground's state estimations fill it):
  neighbours are people with their velocities, static discs and line obstacles viapath's static layer.
* The command is the twist in the robot frame (forward speed, turn rate); navground's kinematics then
  makes it feasible.
"""

from __future__ import annotations

import math
import types
from collections.abc import Callable
from typing import Any

import numpy as np

try:
    from navground import core
except ImportError as error:  # pragma: no cover - depends on the extra
    raise ImportError("viapath's navground behaviour needs navground: pip install 'viapath[navground]'") from error

from viapath.integrations.host import (
    Driver,
    behaviour_options,
    bounded_limits,
    read_options,
    read_waypoints,
    static_layer,
)
from viapath.limits import LIMITS_OPTIONS
from viapath.observation import Observation, Obstacles, RobotState
from viapath.options import Option, OptionError, OptionSet

NAME = "Viapath"
PATH_SAMPLE_M = 0.25  # spacing of the points a navground Path is sampled at

NAVGROUND_OPTIONS = OptionSet(
    [LIMITS_OPTIONS["max_accel_mps2"], LIMITS_OPTIONS["max_turn_accel_radps2"]], owner="navground behavior Viapath"
)

SCHEMA = behaviour_options(NAVGROUND_OPTIONS)
WHERE = f"behavior {NAME}"


def _shortest(value: float) -> float:
    """A float navground kept in single precision, read back at its shortest decimal (0.1, not 0.10000000149)."""
    return value if core.uses_doubles() else float(str(np.float32(value)))


def _plain(option: Option, value: Any) -> Any:
    if option.kind is tuple:
        return tuple(_shortest(float(v)) for v in value)
    if option.kind is float:
        return _shortest(float(value))
    return value


def _schema_modifier(option: Option) -> Callable[[dict[str, Any]], None]:
    def modify(schema: dict[str, Any]) -> None:
        target = schema.setdefault("items", {}) if option.kind is tuple else schema
        if option.minimum is not None:
            target["exclusiveMinimum" if option.exclusive_minimum else "minimum"] = option.minimum
        if option.maximum is not None:
            target["maximum"] = option.maximum
        if option.choices:
            target["enum"] = list(option.choices)

    return modify


def check_property(option: Option, value: Any, where: str) -> None:
    """An :class:`OptionError` naming the property as navground's YAML spells it (``k1``, not ``weights.k1``)."""
    try:
        SCHEMA.validate({option.name: value})
    except OptionError as error:
        raise OptionError([(f"{where}.{option.name}", message) for _, message in error.errors]) from None


def _option_property(option: Option) -> property:
    kind = {bool: "bool", int: "int", float: "float", str: "str", tuple: "float"}[option.kind]
    default = list(option.default) if option.kind is tuple else option.default

    def getter(self: Any) -> Any:
        value = self._values.get(option.name, option.default)
        return list(value) if option.kind is tuple else value

    def setter(self: Any, value: Any) -> None:
        value = _plain(option, value)
        check_property(option, value, WHERE)
        self._values[option.name] = value
        self._driver = None

    registered = core.register(default, option.describe(), _schema_modifier(option), scalar_type_name=kind)(getter)
    return property(registered, setter)


def _path_property() -> property:
    def getter(self: Any) -> list[Any]:
        return [np.asarray(p, dtype=float) for p in self._path]

    def setter(self: Any, value: Any) -> None:
        points = [list(map(_shortest, np.asarray(p, dtype=float).reshape(2))) for p in value]
        read_waypoints(points, f"{WHERE}.path")
        self._path = points
        self._driver = None

    description = "designated path: at least two [x, y] points [m] (empty: from the target)"
    return property(core.register([], description, scalar_type_name="vector")(getter), setter)


def _body(namespace: dict[str, Any]) -> None:
    for option in SCHEMA:
        namespace[option.name] = _option_property(option)
    namespace["path"] = _path_property()
    for name in ("__init__", "get_environment_state", "compute_cmd_internal", "_start", "_observation", "__doc__"):
        namespace[name] = getattr(_Methods, name)


class _Methods:
    """viapath's x-y-t planner, behind its passive-safety shield, following a designated path."""

    _values: dict[str, Any]
    _path: list[Any]
    _driver: Driver | None

    def __init__(self: Any, kinematics: Any = None, radius: float = 0.0) -> None:
        core.Behavior.__init__(self, kinematics, radius)
        self._values = {}
        self._path = []
        self._driver = None
        self._target: np.ndarray | None = None
        self._static: tuple[bytes, Any] | None = None
        self._state = core.GeometricState()

    def get_environment_state(self: Any) -> Any:
        return self._state

    def _start(self: Any, time_step: float) -> bool:
        """Build the planner for this cycle's path; False when there is nothing to follow."""
        settings = read_options(SCHEMA, self._values, where=WHERE)
        position = np.asarray(self.position, dtype=float)
        target = self.target
        waypoints = read_waypoints(self._path, f"{WHERE}.path")
        if waypoints is None and target.path is not None and target.path.length > 0:
            path = target.path
            count = max(2, int(math.ceil(path.length / PATH_SAMPLE_M)) + 1)
            points = np.array([np.asarray(path.curve(s)[0], dtype=float) for s in np.linspace(0, path.length, count)])
            keep = np.concatenate([[True], np.hypot(*np.diff(points, axis=0).T) > 1e-6])
            waypoints = points[keep] if keep.sum() >= 2 else None
        if waypoints is None and target.position is not None:
            goal = np.asarray(target.position, dtype=float)
            if np.hypot(*(goal - position)) <= 1e-6:
                return False
            waypoints = np.array([position, goal])
            self._target = goal
        if waypoints is None:
            return False
        kinematics = self.kinematics
        max_speed = float(self.max_speed)
        turn = float(kinematics.max_angular_speed) if kinematics is not None else math.inf
        driver = Driver(settings)
        tolerance = float(target.position_tolerance) if target.position is not None else math.inf
        driver.start(
            waypoints,
            nominal_speed_mps=min(float(self.optimal_speed), max_speed),
            limits=bounded_limits(max_speed, settings["max_accel_mps2"], turn, settings["max_turn_accel_radps2"]),
            robot_radius_m=float(self.radius),
            dt_s=float(time_step),
            goal_tolerance_m=0.8 * tolerance if tolerance > 0 else 0.05,
        )
        self._driver = driver
        return True

    def _observation(self: Any, time_s: float) -> Observation:
        state = self._state
        twist = self.get_twist(core.Frame.relative)
        robot = RobotState(
            position=np.asarray(self.position, dtype=float).copy(),
            heading_rad=float(self.orientation),
            speed_mps=float(twist.velocity[0]),
            turn_rate_radps=float(twist.angular_speed),
            radius_m=float(self.radius),
        )
        neighbours = list(state.neighbors)
        if neighbours:
            obstacles = Obstacles(
                np.array([n.position for n in neighbours], dtype=float),
                np.array([n.velocity for n in neighbours], dtype=float),
                np.array([n.radius for n in neighbours], dtype=float),
                ids=np.array([n.id for n in neighbours], dtype=np.int64),
            )
        else:
            obstacles = Obstacles.empty()
        discs = np.array([[*d.position, d.radius] for d in state.static_obstacles], dtype=float).reshape(-1, 3)
        lines = np.array([[line.p1, line.p2] for line in state.line_obstacles], dtype=float).reshape(-1, 2, 2)
        key = discs.tobytes() + b"|" + lines.tobytes()
        # Walls and static discs rarely change: the same layer object is kept while they do not, so the
        # guard's sampling of it into discs (cached on the layer) is done once, not every cycle.
        if self._static is None or self._static[0] != key:
            layer = static_layer(circles=[(d[:2], float(d[2])) for d in discs], segments=[lines])
            self._static = (key, layer)
        static = self._static[1]
        return Observation(time_s, robot, obstacles, static)

    def compute_cmd_internal(self: Any, time_step: float) -> Any:
        target = self.target
        new_point = (
            not self._path
            and target.position is not None
            and self._target is not None
            and np.hypot(*(np.asarray(target.position, dtype=float) - self._target)) > 1e-6
        )
        if (self._driver is None or new_point) and not self._start(time_step):
            return core.Twist2((0.0, 0.0), 0.0, frame=core.Frame.relative)
        self._time_s = getattr(self, "_time_s", 0.0) + float(time_step)
        command = self._driver.command(self._observation(self._time_s))
        return core.Twist2((command.speed_mps, 0.0), command.turn_rate_radps, frame=core.Frame.relative)


Viapath = types.new_class(NAME, (core.Behavior,), {"name": NAME}, _body)


def _known_keys() -> set[str]:
    """Every key navground reads from a ``type: Viapath`` block: navground's own and viapath's properties."""
    import yaml

    return set(yaml.safe_load(core.dump(Viapath())) or {}) | {"type", "modulations"}


def check_experiment(text: str, origin: str = "<experiment>") -> list[str]:
    """What is wrong with the ``Viapath`` behaviour blocks of a navground YAML (experiment, scenario, group),
    one message per bad field naming it. navground's reader skips keys no property has, for every
    behaviour, before a behaviour exists: this is where an unknown key is refused."""
    import yaml

    known = _known_keys()
    errors: list[str] = []

    def visit(node: Any, where: str) -> None:
        if isinstance(node, dict):
            if node.get("type") == NAME:
                errors.extend(f"{origin}: {message}" for message in _block_errors(node, where, known))
            for key, value in node.items():
                visit(value, f"{where}.{key}" if where else str(key))
        elif isinstance(node, list):
            for k, value in enumerate(node):
                visit(value, f"{where}.{k}")

    visit(yaml.safe_load(text), "")
    return errors


def _block_errors(block: dict[str, Any], where: str, known: set[str]) -> list[str]:
    errors = []
    for key, value in block.items():
        field = f"{where}.{key}"
        if key not in known:
            errors.append(f"{field}: unknown option {key!r}; Viapath has: {', '.join(sorted(known - {'type'}))}")
        elif isinstance(value, dict) and "sampler" in value:
            continue  # a navground sampler: its values are checked as each run sets them
        elif key in SCHEMA:
            try:
                check_property(SCHEMA[key], value, where)
            except OptionError as error:
                errors.extend(f"{f}: {m}" for f, m in error.errors)
        elif key == "path":
            try:
                read_waypoints(value, field)
            except OptionError as error:
                errors.extend(f"{f}: {m}" for f, m in error.errors)
    return errors


def main(argv: list[str] | None = None) -> int:
    """``python -m viapath.integrations.navground FILE...``: check the Viapath blocks of navground YAML files
    (exit 0: none is wrong, 2: some are, each named)."""
    import sys
    from pathlib import Path

    import yaml

    files = sys.argv[1:] if argv is None else argv
    if not files:
        print("usage: python -m viapath.integrations.navground EXPERIMENT.yaml...", file=sys.stderr)
        return 2
    errors: list[str] = []
    for name in files:
        try:
            errors += check_experiment(Path(name).read_text(), name)
        except (OSError, UnicodeDecodeError, yaml.YAMLError) as error:
            errors.append(f"{name}: cannot read it as YAML: {error}")
    for message in errors:
        print(message, file=sys.stderr)
    return 2 if errors else 0


if __name__ == "__main__":
    raise SystemExit(main())
