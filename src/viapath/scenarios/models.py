"""Scenario files (docs/design.md §4): pydantic models with ``extra="forbid"`` so a typo is an error naming the field.

Every number must be finite and inside its physical range; the loader turns a validation failure
into one message naming the file, the field path, what was expected and what was found.
"""

from __future__ import annotations

import math
from typing import Annotated, Any

from pydantic import (
    BaseModel,
    ConfigDict,
    Discriminator,
    Field,
    NonNegativeFloat,
    PositiveFloat,
    Tag,
    field_validator,
    model_validator,
)

from viapath.limits import LIMITS_OPTIONS, ROBOT_OPTIONS, SUBGOAL_OPTIONS
from viapath.options import OptionSet
from viapath.perception.laser_options import LaserOptions
from viapath.perception.modes import PERCEPTION_MODES
from viapath.static import box_edges, polygon_edges, polyline_edges

MAX_COORDINATE_M = 1.0e6  # m; a scenario spans metres to kilometres, and 1e308 overflows every distance
MAX_SPEED_MPS = 100.0  # m/s; robots and people move at a few m/s
MAX_RADIUS_M = 10.0  # m; the guard stops for a larger obstacle (GuardConfig.max_radius_m)
Coordinate = Annotated[float, Field(ge=-MAX_COORDINATE_M, le=MAX_COORDINATE_M)]
Point = tuple[Coordinate, Coordinate]
Velocity = tuple[
    Annotated[float, Field(ge=-MAX_SPEED_MPS, le=MAX_SPEED_MPS)],
    Annotated[float, Field(ge=-MAX_SPEED_MPS, le=MAX_SPEED_MPS)],
]
Speed = Annotated[float, Field(gt=0.0, le=MAX_SPEED_MPS)]
Radius = Annotated[float, Field(gt=0.0, le=MAX_RADIUS_M)]
MAX_STEPS = 1_000_000  # a day at 10 Hz is 864 000; more is a typo in dt_s that would hang a run
Segment = tuple[Point, Point]


class _Strict(BaseModel):
    model_config = ConfigDict(
        extra="forbid", allow_inf_nan=False, validate_assignment=True, ser_json_inf_nan="constants"
    )


def _field(options: OptionSet, name: str) -> Any:
    """The pydantic field of option ``name``: default, bounds and description from the one schema."""
    return options[name].pydantic_field()[1]


class LimitsSpec(_Strict):
    """The base's limits: :data:`viapath.limits.LIMITS_OPTIONS`."""

    max_speed_mps: float = _field(LIMITS_OPTIONS, "max_speed_mps")
    max_accel_mps2: float = _field(LIMITS_OPTIONS, "max_accel_mps2")
    max_turn_rate_radps: float = _field(LIMITS_OPTIONS, "max_turn_rate_radps")
    max_turn_accel_radps2: float = _field(LIMITS_OPTIONS, "max_turn_accel_radps2")


class RobotSpec(_Strict):
    start: Point
    heading: Annotated[float, Field(ge=-MAX_COORDINATE_M, le=MAX_COORDINATE_M)] = 0.0
    speed: float = _field(ROBOT_OPTIONS, "nominal_speed_mps")
    radius: float = _field(ROBOT_OPTIONS, "robot_radius_m")
    limits: LimitsSpec = Field(default_factory=LimitsSpec)

    @model_validator(mode="after")
    def _speed_within_limits(self) -> RobotSpec:
        if self.speed > self.limits.max_speed_mps:
            raise ValueError(f"speed {self.speed} m/s exceeds limits.max_speed_mps {self.limits.max_speed_mps}")
        return self


class PathSpec(_Strict):
    waypoints: list[Point] = Field(min_length=2)
    half_width: PositiveFloat | None = None
    half_widths: list[PositiveFloat] | None = None

    @model_validator(mode="after")
    def _one_width_per_segment(self) -> PathSpec:
        if self.half_width is None and self.half_widths is None:
            raise ValueError("give half_width (one for every segment) or half_widths (one per segment)")
        if self.half_widths is not None and len(self.half_widths) != len(self.waypoints) - 1:
            raise ValueError(
                f"half_widths needs one value per segment ({len(self.waypoints) - 1}), found {len(self.half_widths)}"
            )
        for a, b in zip(self.waypoints, self.waypoints[1:]):
            if a == b:
                raise ValueError(f"consecutive waypoints must differ, found {list(a)} twice")
        return self

    def widths(self) -> list[float]:
        if self.half_widths is not None:
            return list(self.half_widths)
        assert self.half_width is not None  # the validator asks for one of the two
        return [self.half_width] * (len(self.waypoints) - 1)


class ObstacleSpec(_Strict):
    """A moving disc: constant ``velocity``, or along ``waypoints`` at ``speed`` (optionally looping),
    or along ``waypoints`` reached at the given ``times_s`` (one time for ``start`` and one per
    waypoint: e.g. a precomputed crowd whose speed varies)."""

    start: Point
    radius: Radius = 0.25
    velocity: Velocity | None = None
    waypoints: list[Point] | None = None
    speed: Speed | None = None
    loop: bool = False
    start_time_s: NonNegativeFloat = 0.0  # stands still at ``start`` until then
    times_s: list[NonNegativeFloat] | None = None  # timed waypoints: when it is at start, then each waypoint

    @model_validator(mode="after")
    def _one_motion(self) -> ObstacleSpec:
        if self.waypoints is not None:
            if self.velocity is not None:
                raise ValueError("give velocity or waypoints, not both")
            if self.times_s is not None:
                if self.speed is not None or self.loop:
                    raise ValueError("times_s sets the speeds: give no speed and no loop with it")
                if len(self.times_s) != len(self.waypoints) + 1:
                    raise ValueError(
                        f"times_s needs one time for start and one per waypoint "
                        f"({len(self.waypoints) + 1}), found {len(self.times_s)}"
                    )
                if any(b <= a for a, b in zip(self.times_s, self.times_s[1:])):
                    raise ValueError("times_s must increase strictly")
            elif self.speed is None:
                raise ValueError("an obstacle with waypoints needs a speed (m/s) or times_s")
        elif self.speed is not None or self.times_s is not None:
            raise ValueError("speed and times_s apply only with waypoints; use velocity for constant motion")
        return self


class ReplaySpec(_Strict):
    """Every pedestrian of a recorded trajectory file (ETH/UCY 4-column ``frame id x y``)."""

    file: str
    dt_s: PositiveFloat = 0.4
    start_s: NonNegativeFloat = 0.0
    offset: Point = (0.0, 0.0)
    radius: Radius = 0.25
    react: bool = False  # people give way to the robot (viapath.sim.reactive)


class ReplayItem(_Strict):
    replay: ReplaySpec


def _obstacle_kind(value: Any) -> str:
    if isinstance(value, dict):
        return "replay" if "replay" in value else "moving"
    return "replay" if isinstance(value, ReplayItem) else "moving"


ObstacleItem = Annotated[
    Annotated[ObstacleSpec, Tag("moving")] | Annotated[ReplayItem, Tag("replay")],
    Discriminator(_obstacle_kind),
]


class PlannerSpec(BaseModel):
    """``name`` and the options of that planner, as its option schema defines them (``viapath planners
    NAME`` lists them): validated by the loader against the named planner, so a typo or an option of
    another planner is an error naming the field and the options that planner has. ``params`` is the
    older spelling (a mapping of options) and is merged in."""

    model_config = ConfigDict(extra="allow", allow_inf_nan=False)

    name: str = "viapath"
    params: dict[str, Any] = Field(default_factory=dict, description="options (older spelling)")

    def given(self) -> dict[str, Any]:
        """The options this block sets (nested as in YAML), without the defaults."""
        return {**self.params, **(self.model_extra or {})}


class PerceptionSpec(_Strict):
    """``mode`` and its options: the oracle's noise (``position_noise_m``, ``velocity_noise_mps``; mode
    ``tracked``: ``position_noise_m``, the detections' σ before the tracker) or the laser chain's ``options``
    (:class:`~viapath.perception.laser_options.LaserOptions`)."""

    mode: str = "oracle"
    position_noise_m: NonNegativeFloat = 0.0
    velocity_noise_mps: NonNegativeFloat = 0.0
    options: LaserOptions = Field(  # type: ignore[valid-type]
        default_factory=LaserOptions, description="options for the laser chain (mode laser)"
    )

    @field_validator("mode")
    @classmethod
    def _known_mode(cls, value: str) -> str:
        if value not in PERCEPTION_MODES:
            raise ValueError("expected " + " or ".join(repr(name) for name in PERCEPTION_MODES.ordered()))
        return value

    @model_validator(mode="after")
    def _options_for_the_laser(self) -> PerceptionSpec:
        given = sorted(self.options.model_fields_set)  # type: ignore[attr-defined]
        if self.mode in ("oracle", "tracked") and given:
            raise ValueError(
                f"options ({', '.join(given)}) configure the laser chain; mode {self.mode!r} takes none "
                "(its noise is position_noise_m and velocity_noise_mps): give mode: laser, or drop options"
            )
        if self.mode == "tracked" and self.velocity_noise_mps > 0:
            raise ValueError(
                "velocity_noise_mps: mode 'tracked' takes its velocities from the tracker; white velocity noise "
                "is mode 'oracle' (give 0, or mode: oracle)"
            )
        return self


class _StaticShape(_Strict):
    """Something static the robot can touch; ``until_s`` removes it at that time (a door that opens)."""

    until_s: NonNegativeFloat | None = None

    def edges(self):  # pragma: no cover - interface
        raise NotImplementedError


class WallSpec(_StaticShape):
    """A wall: a polyline through ``points`` (two points: one straight piece)."""

    points: list[Point] = Field(min_length=2)

    def edges(self):
        return polyline_edges(self.points)


class BoxSpec(_StaticShape):
    """A rectangle (a box, a cart, a pillar): ``size`` = (length along ``yaw``, width), m."""

    center: Point
    size: tuple[
        Annotated[float, Field(gt=0.0, le=2 * MAX_COORDINATE_M)],
        Annotated[float, Field(gt=0.0, le=2 * MAX_COORDINATE_M)],
    ]
    yaw: Annotated[float, Field(ge=-MAX_COORDINATE_M, le=MAX_COORDINATE_M)] = 0.0

    @model_validator(mode="after")
    def _corners_within_bounds(self) -> BoxSpec:
        # Every corner within the coordinates a scenario may have, as a wall's or a polygon's points:
        # geometry past them would be dropped or overflow somewhere downstream.
        corners = self.edges()[:, 0]
        if not (abs(corners) <= MAX_COORDINATE_M).all():
            worst = float(abs(corners).max())
            raise ValueError(
                f"size: the box's corners reach {worst:.4g} m; every corner must lie within ±{MAX_COORDINATE_M:g} m"
            )
        return self

    def edges(self):
        return box_edges(self.center, self.size, self.yaw)


class PolygonSpec(_StaticShape):
    """A closed polygon through ``points`` (at least three)."""

    points: list[Point] = Field(min_length=3)

    def edges(self):
        return polygon_edges(self.points)


def _wall_kind(value: Any) -> str:
    return "spec" if isinstance(value, (dict, WallSpec)) else "segment"


WallItem = Annotated[
    Annotated[Segment, Tag("segment")] | Annotated[WallSpec, Tag("spec")],
    Discriminator(_wall_kind),
]


class SubgoalSpec(_Strict):
    """When a subgoal is reached or given up: :data:`viapath.limits.SUBGOAL_OPTIONS`."""

    reach_threshold_m: float = _field(SUBGOAL_OPTIONS, "reach_threshold_m")
    goal_tolerance_m: float = _field(SUBGOAL_OPTIONS, "goal_tolerance_m")
    bypass_distance_m: float = _field(SUBGOAL_OPTIONS, "bypass_distance_m")
    blocked_clearance_m: float = _field(SUBGOAL_OPTIONS, "blocked_clearance_m")


class Scenario(_Strict):
    name: str
    description: str = ""
    robot: RobotSpec
    path: PathSpec
    obstacles: list[ObstacleItem] = Field(default_factory=list)
    walls: list[WallItem] = Field(default_factory=list)
    boxes: list[BoxSpec] = Field(default_factory=list)
    polygons: list[PolygonSpec] = Field(default_factory=list)
    planner: PlannerSpec = Field(default_factory=PlannerSpec)
    perception: PerceptionSpec = Field(default_factory=PerceptionSpec)
    subgoals: SubgoalSpec = Field(default_factory=SubgoalSpec)
    duration_s: PositiveFloat = 60.0
    dt_s: PositiveFloat = 0.1
    seed: int = Field(0, ge=0)  # numpy's generator takes no negative seed

    def static_shapes(self) -> list[tuple[Any, float]]:
        """Every static shape as (edges (E, 2, 2), until_s or inf): walls, boxes, polygons, in that order."""
        shapes = []
        for wall in self.walls:
            if isinstance(wall, WallSpec):
                shapes.append((wall.edges(), math.inf if wall.until_s is None else wall.until_s))
            else:
                shapes.append((polyline_edges(wall), math.inf))
        for shape in (*self.boxes, *self.polygons):
            shapes.append((shape.edges(), math.inf if shape.until_s is None else shape.until_s))
        return shapes

    @field_validator("duration_s")
    @classmethod
    def _not_absurd(cls, value: float) -> float:
        if value > 24 * 3600:
            raise ValueError("duration_s above one day is surely a mistake")
        return value

    @field_validator("dt_s")
    @classmethod
    def _step_within_duration(cls, value: float, info) -> float:
        duration = info.data.get("duration_s")
        if duration is not None and value > duration:
            raise ValueError(f"dt_s must not exceed duration_s ({duration} s): the episode would have no step")
        if duration is not None and duration / value > MAX_STEPS:
            raise ValueError(
                f"duration_s / dt_s = {duration / value:,.0f} steps; at most {MAX_STEPS:,} "
                f"(raise dt_s or shorten duration_s; the scan period is 0.1 s)"
            )
        return value
