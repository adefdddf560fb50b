"""What IR-SIM's and navground's viapath behaviours share: their options, and one cycle through the
shipped planner and shield.

Source: the simulators' own conventions for a selectable behaviour (IR-SIM's ``behavior:`` block of
keyword options, navground's registered properties); viapath's planner protocol
(:mod:`viapath.planning`) and shield (:mod:`viapath.safety`) as they are.

Choices made where the simulators are silent:
* Options come from one schema: the ``viapath`` planner's own :class:`~viapath.options.OptionSet` plus
  :data:`HOST_OPTIONS` (the corridor's half-width, a weights preset, the shield) and whatever the
  simulator adds. A simulator's YAML is checked against it as a scenario's ``planner:`` block is:
  an unknown or out-of-range option is refused with the field named.
* ``preset`` applies a shipped weights preset (``viapath presets``) first; options given beside it win,
  as ``planner: {weights: PRESET, ...}`` does in a scenario.
* The designated path is given (``path``) or, by default, the straight line from where the robot is
  when it first gets a goal to that goal (through every goal, when the simulator gives several).
* The shield is on, with its shipped options, unless ``shield: false``.
* Limits a simulator leaves unbounded (IR-SIM's default acceleration is infinite) are given to viapath
  as the largest its limits schema allows (:data:`viapath.limits.LIMIT_BOUNDS`): the robot may change
  speed within one step, and viapath plans so.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np

from viapath.limits import LIMIT_BOUNDS
from viapath.observation import Command, MotionLimits, Observation
from viapath.options import Option, OptionError, OptionSet, Settings, short_repr
from viapath.path import DesignatedPath, SubgoalPolicy
from viapath.planning import Planner, make_planner, planner_options
from viapath.presets import load_preset, preset_names
from viapath.safety import shielded
from viapath.static import StaticLayer, polygon_edges, polyline_edges

PLANNER = "viapath"

HOST_OPTIONS = OptionSet(
    [
        Option(
            "half_width_m",
            1.0,
            "corridor half-width either side of the designated path",
            "m",
            minimum=0.0,
            exclusive_minimum=True,
            maximum=100.0,
        ),
        Option(
            "preset",
            "none",
            "a shipped weights preset (viapath presets) applied first; options given beside it win",
            choices=("none", *preset_names()),
        ),
        Option("shield", True, "filter every command through viapath's passive-safety shield (shipped options)"),
    ],
    owner="viapath",
)


def behaviour_options(extra: OptionSet | None = None) -> OptionSet:
    """The one schema of a simulator's viapath behaviour: the planner's options, :data:`HOST_OPTIONS`
    and the simulator's own ``extra`` ones."""
    schema = planner_options(PLANNER) + HOST_OPTIONS
    return schema + extra if extra is not None else schema


def given_names(schema: OptionSet, values: Mapping[str, Any]) -> set[str]:
    """The option names ``values`` sets (nested as in YAML, flat or dotted)."""
    names: set[str] = set()
    for key, value in schema.nest(values).items():
        if isinstance(value, Mapping) and key not in schema:
            names.update(str(name) for name in value)
        else:
            names.add(str(key))
    return names


def read_options(schema: OptionSet, values: Mapping[str, Any] | None, where: str) -> Settings:
    """``values`` checked against ``schema`` (an :class:`OptionError` naming each bad field, prefixed by
    ``where``), every option filled in: the preset's values first, then the ones given."""
    values = dict(values or {})
    settings = schema.validate(values, where=where)
    if settings["preset"] == "none":
        return settings
    preset = load_preset(settings["preset"])
    given = given_names(schema, values)
    merged = {**dict(settings), **{k: v for k, v in preset.options.items() if k not in given}}
    return Settings(merged)


def read_waypoints(value: Any, field: str) -> np.ndarray | None:
    """A designated path given as a list of at least two [x, y] points (None: not given)."""
    if value is None or (isinstance(value, (list, tuple)) and len(value) == 0):
        return None
    try:
        points = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        points = np.zeros((0,))
    if points.ndim != 2 or points.shape[1] != 2 or len(points) < 2 or not np.isfinite(points).all():
        raise OptionError([(field, f"expected a list of at least two [x, y] points; found {short_repr(value)}")])
    if (np.hypot(*np.diff(points, axis=0).T) <= 1e-9).any():
        raise OptionError([(field, "consecutive points must differ")])
    return points


def bounded_limits(
    max_speed_mps: float, max_accel_mps2: float, max_turn_rate_radps: float, max_turn_accel_radps2: float
) -> MotionLimits:
    """A simulator's limits within viapath's limits schema (an infinite one becomes the largest allowed)."""
    values = dict(
        max_speed_mps=max_speed_mps,
        max_accel_mps2=max_accel_mps2,
        max_turn_rate_radps=max_turn_rate_radps,
        max_turn_accel_radps2=max_turn_accel_radps2,
    )
    clipped = {}
    for name, value in values.items():
        low, high = LIMIT_BOUNDS[name]
        number = float(value)
        clipped[name] = high if math.isnan(number) else min(max(number, low), high)
    return MotionLimits(**clipped)


def static_layer(
    polygons: Iterable[np.ndarray] = (),
    polylines: Iterable[np.ndarray] = (),
    circles: Iterable[tuple[np.ndarray, float]] = (),
    segments: Iterable[np.ndarray] = (),
) -> StaticLayer:
    """Static geometry as viapath's static layer: closed outlines (K, 2), open polylines (K, 2), circles
    (a point of the circle's radius) and loose segments (M, 2, 2), one shape id each."""
    shapes: list[np.ndarray] = []
    for outline in polygons:
        shapes.append(polygon_edges(outline))
    for line in polylines:
        shapes.append(polyline_edges(line))
    for edges in segments:
        shapes.append(np.asarray(edges, dtype=float).reshape(-1, 2, 2))
    pads = [np.zeros(len(edges)) for edges in shapes]  # exact outlines; a circle is a point padded by its radius
    for centre, radius in circles:
        point = np.asarray(centre, dtype=float).reshape(1, 1, 2)
        shapes.append(np.concatenate([point, point], axis=1))
        pads.append(np.array([float(radius)]))
    shapes_kept = [(s, p) for s, p in zip(shapes, pads) if len(s)]
    if not shapes_kept:
        return StaticLayer.empty()
    ids = np.concatenate([np.full(len(s), k, dtype=np.int64) for k, (s, _) in enumerate(shapes_kept)])
    padding = np.concatenate([p for _, p in shapes_kept])
    return StaticLayer(np.concatenate([s for s, _ in shapes_kept]), ids, padding if padding.any() else None)


class Driver:
    """The planner (behind the shield) of one simulated robot, built on its first cycle."""

    def __init__(self, settings: Settings) -> None:
        self.settings = settings
        self.planner: Planner | None = None
        self.path: DesignatedPath | None = None

    def start(
        self,
        waypoints: np.ndarray,
        *,
        nominal_speed_mps: float,
        limits: MotionLimits,
        robot_radius_m: float,
        dt_s: float,
        goal_tolerance_m: float,
        reach_threshold_m: float | None = None,
    ) -> None:
        """Build the planner for ``waypoints`` (the last is the goal) with the robot's description; within
        ``goal_tolerance_m`` of the goal it stops (and switches from an intermediate subgoal within
        ``reach_threshold_m`` when given), never farther than viapath's own defaults."""
        settings = self.settings
        names = planner_options(PLANNER).names
        self.path = DesignatedPath(waypoints, half_width_m=settings["half_width_m"])
        default = SubgoalPolicy()
        reach = (
            default.reach_threshold_m
            if reach_threshold_m is None
            else min(default.reach_threshold_m, reach_threshold_m)
        )
        policy = SubgoalPolicy(
            reach_threshold_m=reach, goal_tolerance_m=min(default.goal_tolerance_m, goal_tolerance_m)
        )
        planner = make_planner(
            PLANNER,
            self.path,
            nominal_speed_mps=nominal_speed_mps,
            limits=limits,
            robot_radius_m=robot_radius_m,
            subgoal_policy=policy,
            **{name: settings[name] for name in names},
        )
        self.planner = shielded(planner, bool(settings["shield"]), dt_s, planner_name=PLANNER)

    @property
    def started(self) -> bool:
        return self.planner is not None

    def command(self, observation: Observation) -> Command:
        """This cycle's command: a stop before :meth:`start`, and for anything not finite."""
        if self.planner is None:
            return Command.stop()
        command = self.planner.plan(observation).command
        if not (math.isfinite(command.speed_mps) and math.isfinite(command.turn_rate_radps)):
            return Command.stop()
        return command
