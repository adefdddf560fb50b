"""What the planner saw and chose in one cycle, as plain numpy: the content every view draws.

Source: docs/design.md §9 (seeing a run) and §2 (the x-y-t picture of the paper, Yamada-Sa-Ohya Fig. 4:
people as oblique cylinders ``|x - c_i - v_i t| <= R_i`` over the horizon, the robot's plan as a
polyline through its via points, time as the height). The Foxglove writer
(:mod:`viapath.viz.foxglove`) and the ROS 2 node's MarkerArray both build their messages from a
:class:`CycleScene`, so both views show the same thing. This module imports no plotting, no
Foxglove and no ROS: numpy and the core only.

What the sources leave open and we chose:
* The x-y-t cylinder of person i has the *combined* radius ``R_i = r_robot + r_i`` (the robot is
  the point at the centre of its disc, as in the paper's figure), optionally grown into the
  planner's uncertainty cone ``R_i + min(k·σ_v,i·t, cap)`` (``ForecastSettings``: k and the cap are
  the viapath planner's ``uncertainty_sigmas`` and ``max_inflation_m``). Safety margins are not
  drawn: the picture shows the forecast, not the planner's tolerances.
* Time in the x-y-t view is relative to the planning cycle (t = 0 at the robot) and is drawn as
  height ``z = t · time_scale_m_per_s`` (0.5 m per second by default, so a 10 s horizon is 5 m tall
  beside a scene a few metres wide).
* The plan's times: a plan that records ``extras["waypoint_times_s"]`` (one per waypoint) is drawn
  with them; one that first slows down (``extras["slow_s"]`` with ``speed_mps`` the slow speed and
  ``extras["speed_after_mps"]``) drives at the slow speed for ``slow_s`` and on at the speed after;
  any other plan drives its polyline at ``speed_mps`` (the viapath planner's via points lie on the
  reachable cone of that speed, so this is exact for it). A plan at speed 0 stands at the robot for
  the whole horizon. The polyline ends at the horizon or at its last waypoint, whichever is first.
* The runner-up is the cheapest finite candidate other than the chosen one.
* The per-term cost breakdown is ``extras["cost_terms"]`` (``{"chosen": {term: value},
  "runner_up": {term: value}}``) when the planner provides it; otherwise only total costs exist.
* Shield interventions are read from ``extras["shield"]["intervened"]`` or
  ``extras["shield_intervened"]`` (whichever the planner's decision carries); absent means none.
* Clearance is surface-to-surface to the *true* people when the simulator gives them, else to the
  tracked ones.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np

from viapath.observation import Obstacles


@dataclass(frozen=True)
class ForecastSettings:
    """How far and how wide the x-y-t view forecasts people (defaults: the viapath planner's)."""

    horizon_s: float = 10.0
    uncertainty_sigmas: float = 2.0
    max_inflation_m: float = 0.15
    time_scale_m_per_s: float = 0.5  # height per second of forecast in the x-y-t view

    def __post_init__(self) -> None:
        for name in ("horizon_s", "time_scale_m_per_s"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"ForecastSettings.{name}: expected a finite number > 0, found {value}")
        for name in ("uncertainty_sigmas", "max_inflation_m"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value >= 0):
                raise ValueError(f"ForecastSettings.{name}: expected a finite number >= 0, found {value}")

    @classmethod
    def from_planner(cls, planner: Any, **overrides) -> ForecastSettings:
        """The planner's horizon and uncertainty cone where it has them (``planner.config`` or the
        planner itself), the defaults elsewhere."""
        values: dict[str, float] = {}
        settings = getattr(planner, "settings", None) or {}
        for source in (planner, settings):
            for name in ("horizon_s", "uncertainty_sigmas", "max_inflation_m"):
                value = source.get(name) if isinstance(source, Mapping) else getattr(source, name, None)
                if isinstance(value, (int, float)) and np.isfinite(value):
                    values[name] = float(value)
        values.update(overrides)
        return cls(**values)


@dataclass(frozen=True)
class PersonForecast:
    """One tracked person under the constant-velocity forecast, as the x-y-t view draws it."""

    id: int
    position: np.ndarray  # (2,) m, at the planning time
    velocity: np.ndarray  # (2,) m/s
    radius_m: float  # the person's own radius
    combined_radius_m: float  # r_person + r_robot: the disc the robot's centre must keep out of
    position_sigma_m: float
    velocity_sigma_mps: float

    def centre_at(self, t_s) -> np.ndarray:
        """Forecast centre at times ``t_s`` after the planning time: (..., 2)."""
        t = np.asarray(t_s, dtype=float)
        return self.position + t[..., None] * self.velocity

    def radius_at(self, t_s, settings: ForecastSettings, cone: bool = True) -> np.ndarray:
        """Radius of the x-y-t cylinder (cone when ``cone`` and σ_v > 0) at times ``t_s``."""
        t = np.asarray(t_s, dtype=float)
        radius = np.full(t.shape, self.combined_radius_m)
        if cone:
            radius = radius + np.minimum(
                settings.uncertainty_sigmas * self.velocity_sigma_mps * t, settings.max_inflation_m
            )
        return radius

    def ring_times_s(self, settings: ForecastSettings, cone: bool = True) -> np.ndarray:
        """Times at which the surface changes slope (0, the end of cone growth, the horizon): between
        two of them the surface is exactly ruled, so rings at these times describe it exactly."""
        times = [0.0, settings.horizon_s]
        growth = settings.uncertainty_sigmas * self.velocity_sigma_mps
        if cone and growth > 0:
            cap_s = settings.max_inflation_m / growth
            if 0.0 < cap_s < settings.horizon_s:
                times.insert(1, cap_s)
        return np.array(times)


@dataclass(frozen=True)
class XYTScene:
    """The paper's Fig. 4 for one cycle: times relative to the planning time, height = t · scale."""

    settings: ForecastSettings
    persons: list[PersonForecast]
    plan_xyt: np.ndarray  # (K, 3) x, y, t of the robot's plan from the robot (t = 0) on
    via_points_xyt: np.ndarray  # (V, 3)
    cone: bool = True
    # (P, 6) x, y, vx, vy, combined radius, σ_v of the persons, in their order (None: read from them);
    # the builder gives it from the tracks' arrays so that the rings need no loop over persons.
    person_fields: np.ndarray | None = None

    def rings(self, index: int, segments: int = 24) -> np.ndarray:
        """Circles of person ``index``'s cylinder at its ring times: (R, segments, 3) in x, y, t."""
        person = self.persons[index]
        times = person.ring_times_s(self.settings, self.cone)
        centres = person.centre_at(times)
        radii = person.radius_at(times, self.settings, self.cone)
        circle = _unit_circle(segments)
        xy = centres[:, None, :] + radii[:, None, None] * circle[None]
        out = np.empty((len(times), segments, 3))
        out[..., :2] = xy
        out[..., 2] = times[:, None]
        return out

    def mesh_indexed(self, index: int, segments: int = 24) -> tuple[np.ndarray, np.ndarray]:
        """Person ``index``'s oblique cylinder as shared vertices (V, 3) in x, y, t and triangles
        (T, 3) of vertex indices: the side between consecutive rings and both caps. The vertices are
        the rings' points, then the centres of the bottom and the top cap."""
        rings = self.rings(index, segments)
        count = len(rings)
        vertices = np.concatenate([rings.reshape(-1, 3), rings[[0, -1]].mean(axis=1)])
        return vertices, _mesh_triangles(count, segments)

    def all_rings(self, segments: int = 24) -> np.ndarray:
        """Every person's cylinder as three rings each, (P, 3, segments, 3) in x, y, t, in one go:
        at 0, where the cone stops growing (or half the horizon when it does not within it), and at
        the horizon. Between them the surface is ruled, so these rings describe it exactly."""
        return self.all_rings_and_centres(segments)[0]

    def all_rings_and_centres(self, segments: int = 24) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`all_rings` and the rings' centres (P, 3, 3) in x, y, t: the forecast position at
        each ring's time (the cylinder's axis; the caps' centres)."""
        count = len(self.persons)
        if count == 0:
            return np.zeros((0, 3, segments, 3)), np.zeros((0, 3, 3))
        settings = self.settings
        horizon = settings.horizon_s
        # One (P, 6) array of what the rings depend on: fewer, larger numpy calls (this runs every cycle).
        fields = self.person_fields
        if fields is None:
            fields = np.array(
                [(*p.position, *p.velocity, p.combined_radius_m, p.velocity_sigma_mps) for p in self.persons]
            )
        growth = settings.uncertainty_sigmas * fields[:, 5] if self.cone else np.zeros(count)
        growing = growth > 0
        cap = np.full(count, np.inf)
        cap[growing] = settings.max_inflation_m / growth[growing]
        times = np.empty((count, 3))
        times[:, 0] = 0.0
        times[:, 1] = np.where((cap > 0) & (cap < horizon), cap, 0.5 * horizon)
        times[:, 2] = horizon
        radii = fields[:, 4:5] + np.minimum(growth[:, None] * times, settings.max_inflation_m)
        centres = np.empty((count, 3, 3))
        centres[..., :2] = fields[:, None, 0:2] + times[..., None] * fields[:, None, 2:4]
        centres[..., 2] = times
        out = np.empty((count, 3, segments, 3))
        out[..., :2] = centres[:, :, None, :2] + radii[:, :, None, None] * _unit_circle(segments)
        out[..., 2] = times[:, :, None]
        return out, centres

    def mesh(self, index: int, segments: int = 24) -> np.ndarray:
        """Triangles (T, 3, 3) in x, y, t of person ``index``'s oblique cylinder: side and both caps."""
        vertices, triangles = self.mesh_indexed(index, segments)
        return vertices[triangles]

    def axis_xyt(self, index: int) -> np.ndarray:
        """The cylinder's axis (the forecast centre) from t = 0 to the horizon: (2, 3)."""
        person = self.persons[index]
        times = np.array([0.0, self.settings.horizon_s])
        return np.column_stack([person.centre_at(times), times])


@dataclass(frozen=True)
class ScannerView:
    """One scan in its scanner's frame, with the mounting pose in the robot (base) frame."""

    name: str
    mount_pose: np.ndarray  # (3,) x, y, yaw in the robot frame
    angle_min_rad: float
    angle_increment_rad: float
    ranges_m: np.ndarray  # (n,) as the driver reported them (inf / NaN / 0 = invalid)
    range_min_m: float
    range_max_m: float

    @property
    def angle_max_rad(self) -> float:
        return self.angle_min_rad + (len(self.ranges_m) - 1) * self.angle_increment_rad


@dataclass(frozen=True)
class PlanView:
    """The plan of one cycle: every candidate, the chosen one, its via points and costs."""

    status: str
    speed_mps: float
    target: np.ndarray  # (2,)
    via_points: np.ndarray  # (V, 2)
    waypoints: np.ndarray  # (W, 2) chosen polyline from the robot
    candidate_polylines: list[np.ndarray]
    candidate_costs: np.ndarray  # (C,)
    chosen: int | None
    runner_up: int | None
    cost_terms: dict[str, dict[str, float]] | None  # {"chosen": {...}, "runner_up": {...}} when given
    extras: dict[str, Any]

    @property
    def chosen_cost(self) -> float | None:
        return _cost(self.candidate_costs, self.chosen)

    @property
    def runner_up_cost(self) -> float | None:
        return _cost(self.candidate_costs, self.runner_up)


@dataclass(frozen=True)
class CycleScene:
    """Everything one view needs for one planning cycle (world frame unless said otherwise)."""

    step: int
    time_s: float
    robot_pose: np.ndarray  # (3,) x, y, heading
    robot_speed_mps: float
    robot_turn_rate_radps: float
    robot_radius_m: float
    command: tuple[float, float]  # (v, ω) commanded this cycle
    tracks: Obstacles  # what the planner was told
    detections_world: np.ndarray  # (D, 2) laser detections this cycle (empty for the oracle)
    detection_radii_m: np.ndarray  # (D,)
    scan_points_world: np.ndarray  # (M, 2)
    scanners: list[ScannerView]
    blind_sectors_rad: list[tuple[float, float]]  # robot frame, (start, end)
    blind_polygon_world: np.ndarray  # (B, 2), empty without laser
    true_people: Obstacles | None  # the simulator's truth, when known
    subgoal: np.ndarray  # (2,)
    subgoal_index: int
    plan: PlanView
    xyt: XYTScene
    series: dict[str, float]  # speed, turn rate, clearance, lateral deviation, plan time, shield count
    static_segments: np.ndarray = field(default_factory=lambda: np.zeros((0, 2, 2)))  # (S, 2, 2) the static layer told

    def footprint(self, segments: int = 32) -> np.ndarray:
        """The robot's disc as a closed polygon in the robot (base) frame: (segments + 1, 2)."""
        return circle_polygon(np.zeros(2), self.robot_radius_m, segments)


@dataclass(frozen=True)
class PathView:
    """The designated path and its corridor: the same for every cycle of a run."""

    waypoints: np.ndarray  # (W, 2)
    half_widths_m: np.ndarray  # (W - 1,)
    corridor_outlines: list[np.ndarray]  # one closed capsule outline per segment


def path_view(path, resolution: int = 24) -> PathView:
    """Path and corridor outlines (one capsule per segment: the corridor is their union)."""
    outlines = []
    for a, d, length, hw in zip(
        path.segment_starts, path.segment_directions, path.segment_lengths_m, path.half_widths_m
    ):
        normal = np.array([-d[1], d[0]])
        angle0 = np.arctan2(normal[1], normal[0])
        end = a + d * length + hw * _unit(np.linspace(angle0 - np.pi, angle0, resolution))
        start = a + hw * _unit(np.linspace(angle0, angle0 + np.pi, resolution))
        outline = np.vstack([end, start])
        outlines.append(np.vstack([outline, outline[:1]]))
    return PathView(np.asarray(path.waypoints, dtype=float), np.asarray(path.half_widths_m, dtype=float), outlines)


def static_segments_of(observation) -> np.ndarray:
    """(S, 2, 2) the observation's static layer (an observation as the MCAP writer rebuilds it holds the
    segments alone)."""
    segments = getattr(observation, "static_segments", None)
    if segments is None:
        static = getattr(observation, "static", None)
        segments = np.zeros((0, 2, 2)) if static is None else static.segments
    return np.asarray(segments, dtype=float).reshape(-1, 2, 2)


class SceneBuilder:
    """Builds one :class:`CycleScene` per planning cycle of a run (keeps the running counts)."""

    def __init__(self, path, robot_radius_m: float, settings: ForecastSettings | None = None, cone: bool = True):
        self.path = path
        self.path_view = path_view(path)
        # The path's segments as plain numbers, for the lateral deviation of one point per cycle.
        self._segments = list(
            zip(
                np.asarray(path.segment_starts, dtype=float).tolist(),
                np.asarray(path.segment_directions, dtype=float).tolist(),
                np.asarray(path.segment_lengths_m, dtype=float).tolist(),
            )
        )
        self.robot_radius_m = float(robot_radius_m)
        self.settings = settings or ForecastSettings()
        self.cone = cone
        self.shield_interventions = 0

    def build(
        self,
        step: int,
        time_s: float,
        robot_pose,
        robot_speed_mps: float,
        robot_turn_rate_radps: float,
        observation,
        decision,
        plan_time_ms: float = float("nan"),
        perception: Any = None,
        true_people: Obstacles | None = None,
        perception_parts: tuple | None = None,
    ) -> CycleScene:
        """The scene of one cycle. ``perception``: the perception object (its last scans, detections
        and blind region are drawn when it has them, as the laser chain does); or, instead of it,
        ``perception_parts`` already taken from it (what a writer in another process receives)."""
        pose = np.asarray(robot_pose, dtype=float).reshape(3)
        tracks = observation.obstacles.finite()
        plan = decision.plan
        extras = dict(plan.extras or {})
        plan_view = _plan_view(plan, extras)
        if _shield_intervened(extras):
            self.shield_interventions += 1
        parts = perception_parts if perception_parts is not None else perception_parts_of(perception)
        horizon = self.settings.horizon_s
        fields = (
            np.column_stack(
                [tracks.positions, tracks.velocities, tracks.radii_m + self.robot_radius_m, tracks.velocity_sigma_mps]
            )
            if len(tracks)
            else None
        )
        xyt = XYTScene(
            self.settings,
            _persons(tracks, self.robot_radius_m),
            plan_xyt(pose[:2], plan, horizon),
            _via_xyt(pose[:2], plan, horizon),
            self.cone,
            fields,
        )
        people = true_people if true_people is not None else tracks
        series = {
            "speed_mps": float(robot_speed_mps),
            "turn_rate_radps": float(robot_turn_rate_radps),
            "command_speed_mps": float(decision.command.speed_mps),
            "command_turn_rate_radps": float(decision.command.turn_rate_radps),
            "clearance_m": clearance_m(pose[:2], self.robot_radius_m, people),
            "lateral_deviation_m": lateral_deviation_m(self._segments, float(pose[0]), float(pose[1])),
            "plan_time_ms": float(plan_time_ms),
            "shield_interventions": int(self.shield_interventions),
            "tracks": int(len(tracks)),
            "candidates": int(len(plan_view.candidate_costs)),
        }
        return CycleScene(
            step=int(step),
            time_s=float(time_s),
            robot_pose=pose,
            robot_speed_mps=float(robot_speed_mps),
            robot_turn_rate_radps=float(robot_turn_rate_radps),
            robot_radius_m=self.robot_radius_m,
            command=(float(decision.command.speed_mps), float(decision.command.turn_rate_radps)),
            tracks=tracks,
            **dict(zip(PERCEPTION_PART_FIELDS, parts, strict=True)),
            true_people=true_people,
            subgoal=np.asarray(plan.target if plan.status == "goal" else self._subgoal(plan), dtype=float),
            subgoal_index=int(plan.subgoal_index),
            plan=plan_view,
            xyt=xyt,
            series=series,
            static_segments=static_segments_of(observation),
        )

    def _subgoal(self, plan) -> np.ndarray:
        index = min(max(int(plan.subgoal_index), 0), len(self.path.waypoints) - 1)
        return self.path.waypoints[index]


# -- pieces ----------------------------------------------------------------------------------------


def plan_xyt(robot_position, plan, horizon_s: float) -> np.ndarray:
    """The robot's plan as (x, y, t) from the robot at t = 0, up to the horizon (see module notes)."""
    start = np.asarray(robot_position, dtype=float).reshape(2)
    line = np.asarray(plan.waypoints, dtype=float).reshape(-1, 2)
    if len(line) == 0:
        line = np.array([start, np.asarray(plan.target, dtype=float).reshape(2)])
    if math.hypot(line[0, 0] - start[0], line[0, 1] - start[1]) > 1e-9:
        line = np.vstack([start, line])
    extras = plan.extras or {}
    times = extras.get("waypoint_times_s")
    if times is not None and len(times) == len(plan.waypoints) and len(line) == len(plan.waypoints):
        xyt = np.column_stack([line, np.asarray(times, dtype=float)])
        return _clip_to_horizon(xyt, horizon_s)
    # Arc length at each point (this runs every cycle on a few points: plain slicing, no np.diff).
    steps = line[1:] - line[:-1]
    lengths = np.zeros(len(line))
    np.cumsum(np.hypot(steps[:, 0], steps[:, 1]), out=lengths[1:])
    speed = float(plan.speed_mps)
    slow_s = float(extras.get("slow_s", 0.0) or 0.0)
    after = extras.get("speed_after_mps")
    if slow_s > 0 and after is not None and float(after) > 0:
        # Slow (or stand) for slow_s, then on at the speed after.
        slow_length = max(speed, 0.0) * slow_s
        before = lengths[(lengths > 0) & (lengths < slow_length)]
        beyond = lengths[lengths > slow_length]
        arc = np.concatenate([[0.0], before, [slow_length], beyond])
        t = np.concatenate(
            [[0.0], before / speed if speed > 0 else before, [slow_s], slow_s + (beyond - slow_length) / float(after)]
        )
        points = np.column_stack([np.interp(arc, lengths, line[:, 0]), np.interp(arc, lengths, line[:, 1])])
        return _clip_to_horizon(np.column_stack([points, t]), horizon_s)
    if speed <= 1e-9:
        return np.array([[start[0], start[1], 0.0], [start[0], start[1], horizon_s]])
    xyt = np.empty((len(line), 3))
    xyt[:, :2], xyt[:, 2] = line, lengths / speed
    return _clip_to_horizon(xyt, horizon_s)


def lateral_deviation_m(segments: list, x: float, y: float) -> float:
    """:meth:`viapath.path.DesignatedPath.lateral_deviation` of one point, the same steps in scalar
    arithmetic (a path has a few segments: numpy's per-call cost was most of it). ``segments``:
    ``((start_x, start_y), (direction_x, direction_y), length_m)`` per segment."""
    best, side = math.inf, 1.0
    for (sx, sy), (dx, dy), length in segments:
        rx, ry = x - sx, y - sy
        along = min(max(rx * dx + ry * dy, 0.0), length)
        distance = math.hypot(x - (sx + along * dx), y - (sy + along * dy))
        if distance < best:  # the first nearest segment, as argmin
            cross = dx * ry - dy * rx
            best, side = distance, (-1.0 if cross < 0 else 1.0)
    return side * best


def _clip_to_horizon(xyt: np.ndarray, horizon_s: float) -> np.ndarray:
    inside = xyt[:, 2] <= horizon_s + 1e-12
    if inside.all():
        return xyt
    last = int(np.flatnonzero(inside)[-1])
    a, b = xyt[last], xyt[last + 1]
    fraction = (horizon_s - a[2]) / max(b[2] - a[2], 1e-12)
    out = np.empty((last + 2, 3))  # the points inside, then the one at the horizon
    out[: last + 1] = xyt[: last + 1]
    out[last + 1] = a + fraction * (b - a)
    return out


def _via_xyt(robot_position, plan, horizon_s: float, line: np.ndarray | None = None) -> np.ndarray:
    """The via points at the times the plan passes them (those past the horizon left out);
    ``line``: the plan's whole (x, y, t) polyline when already computed."""
    via = np.asarray(plan.via_points, dtype=float).reshape(-1, 2)
    if len(via) == 0:
        return np.zeros((0, 3))
    if line is None:
        line = plan_xyt(robot_position, plan, np.inf)
    rows = []
    for point in via:
        distance = np.hypot(*(line[:, :2] - point).T)
        k = int(np.argmin(distance))
        if distance[k] < 1e-6 and line[k, 2] <= horizon_s + 1e-12:
            rows.append(line[k])
    return np.array(rows).reshape(-1, 3)


def _persons(tracks: Obstacles, robot_radius_m: float) -> list[PersonForecast]:
    # Each person's position and velocity are rows of private copies; the scalars read in one go
    # (a crowd's cycle: one numpy call per field, not per person and field).
    positions, velocities = tracks.positions.copy(), tracks.velocities.copy()
    return [
        PersonForecast(int(track), positions[i], velocities[i], radius, combined, position_sigma, velocity_sigma)
        for i, (track, radius, combined, position_sigma, velocity_sigma) in enumerate(
            zip(
                tracks.ids.tolist(),
                tracks.radii_m.tolist(),
                (tracks.radii_m + robot_radius_m).tolist(),
                tracks.position_sigma_m.tolist(),
                tracks.velocity_sigma_mps.tolist(),
            )
        )
    ]


def _plan_view(plan, extras: dict) -> PlanView:
    costs = np.asarray(plan.candidate_costs, dtype=float).reshape(-1)
    chosen = None if plan.chosen is None or not (0 <= int(plan.chosen) < max(len(costs), 1)) else int(plan.chosen)
    runner_up = None
    if len(costs) > 1:
        order = [int(i) for i in np.argsort(costs, kind="stable") if np.isfinite(costs[i]) and i != chosen]
        runner_up = order[0] if order else None
    terms = extras.get("cost_terms")
    if not (isinstance(terms, dict) and isinstance(terms.get("chosen"), dict)):
        terms = None
    return PlanView(
        status=str(plan.status),
        speed_mps=float(plan.speed_mps),
        target=np.asarray(plan.target, dtype=float).reshape(2),
        via_points=np.asarray(plan.via_points, dtype=float).reshape(-1, 2),
        waypoints=np.asarray(plan.waypoints, dtype=float).reshape(-1, 2),
        candidate_polylines=[np.asarray(p, dtype=float).reshape(-1, 2) for p in plan.candidate_polylines],
        candidate_costs=costs,
        chosen=chosen,
        runner_up=runner_up,
        cost_terms=terms,
        extras=extras,
    )


#: The :class:`CycleScene` fields that :func:`perception_parts_of` returns, in its order.
PERCEPTION_PART_FIELDS = (
    "scanners",
    "detections_world",
    "detection_radii_m",
    "scan_points_world",
    "blind_sectors_rad",
    "blind_polygon_world",
)


def perception_parts_of(perception):
    """Scans in scanner frames, detections, scan points and blind region of a perception object
    that has them (the laser chain); empty for the oracle."""
    scanners: list[ScannerView] = []
    if perception is None:
        return (scanners, *perception_arrays_of(None))
    models = getattr(perception, "scanners", ()) or ()
    scans = getattr(perception, "last_scans", None) or []
    for model, ranges in zip(models, scans):
        scanners.append(
            ScannerView(
                str(model.name),
                np.asarray(model.mount_pose(), dtype=float),
                float(model.angle_min_rad),
                float(model.angle_increment_rad),
                np.asarray(ranges, dtype=float).reshape(-1),
                float(model.range_min_m),
                float(model.range_max_m),
            )
        )
    return (scanners, *perception_arrays_of(perception))


def perception_arrays_of(perception):
    """The part of :func:`perception_parts_of` that changes every cycle: detections (D, 2) and their
    radii, scan points (M, 2), blind sectors and the blind region's polygon (B, 2)."""
    empty2 = np.zeros((0, 2))
    if perception is None:
        return empty2, np.zeros(0), empty2, [], empty2
    detections = getattr(perception, "last_detections_world", None)
    centres = np.asarray(getattr(detections, "centres", empty2), dtype=float).reshape(-1, 2)
    radii = np.asarray(getattr(detections, "radii_m", np.zeros(len(centres))), dtype=float).reshape(-1)
    points = getattr(perception, "last_points_world", None)
    points = empty2 if points is None else np.asarray(points, dtype=float).reshape(-1, 2)
    sectors = [(float(a), float(b)) for a, b in (getattr(perception, "blind_sectors", None) or [])]
    blind = empty2
    polygon = getattr(perception, "blind_polygon_world", None)
    if callable(polygon) and sectors:
        blind = np.asarray(polygon(), dtype=float).reshape(-1, 2)
    return centres, radii, points, sectors, blind


def _shield_intervened(extras: dict) -> bool:
    shield = extras.get("shield")
    if isinstance(shield, dict) and shield.get("intervened"):
        return True
    return bool(extras.get("shield_intervened", False))


def clearance_m(position, robot_radius_m: float, people: Obstacles | None) -> float:
    """Surface-to-surface distance from the robot to the nearest person (inf with nobody)."""
    if people is None or len(people) == 0:
        return float("inf")
    positions, radii = people.positions, people.radii_m
    present = np.isfinite(positions).all(axis=1)
    if not present.all():  # (the writer's true people are all present: no copies then)
        if not present.any():
            return float("inf")
        positions, radii = positions[present], radii[present]
    offsets = positions - np.asarray(position, dtype=float)
    return float((np.hypot(offsets[:, 0], offsets[:, 1]) - radii - robot_radius_m).min())


def circle_polygon(centre, radius_m: float, segments: int = 32) -> np.ndarray:
    """A closed circle outline (segments + 1, 2)."""
    return np.asarray(centre, dtype=float) + radius_m * _closed_unit_circle(segments)


def candidate_colour(cost: float, lowest: float, highest: float) -> tuple[float, float, float, float]:
    """Colour of a candidate by its cost E: green (cheapest) to red (dearest), RGBA in 0..1."""
    if not np.isfinite(cost):
        return (0.5, 0.5, 0.5, 0.25)
    span = highest - lowest
    u = 0.0 if span <= 1e-12 else float(np.clip((cost - lowest) / span, 0.0, 1.0))
    return (u, 1.0 - 0.6 * u, 0.1, 0.6)


@lru_cache(maxsize=16)
def _unit_circle(segments: int) -> np.ndarray:
    """``segments`` points of the unit circle (read-only, shared)."""
    circle = _unit(np.linspace(0.0, 2.0 * np.pi, segments, endpoint=False))
    circle.setflags(write=False)
    return circle


@lru_cache(maxsize=16)
def _closed_unit_circle(segments: int) -> np.ndarray:
    circle = _unit(np.linspace(0.0, 2.0 * np.pi, segments + 1))
    circle.setflags(write=False)
    return circle


@lru_cache(maxsize=16)
def _mesh_triangles(rings: int, segments: int) -> np.ndarray:
    """Vertex indices of the side between ``rings`` consecutive rings and of the two caps."""
    k = np.arange(segments)
    nxt = (k + 1) % segments
    parts = []
    for r in range(rings - 1):
        lower, upper = r * segments, (r + 1) * segments
        parts.append(np.stack([lower + k, lower + nxt, upper + k], axis=1))
        parts.append(np.stack([lower + nxt, upper + nxt, upper + k], axis=1))
    bottom, top = rings * segments, rings * segments + 1
    last = (rings - 1) * segments
    parts.append(np.stack([np.full(segments, bottom), k, nxt], axis=1))
    parts.append(np.stack([np.full(segments, top), last + k, last + nxt], axis=1))
    triangles = np.concatenate(parts)
    triangles.setflags(write=False)
    return triangles


def _unit(angles) -> np.ndarray:
    angles = np.asarray(angles, dtype=float)
    return np.stack([np.cos(angles), np.sin(angles)], axis=-1)


def _cost(costs: np.ndarray, index: int | None) -> float | None:
    if index is None or not (0 <= index < len(costs)):
        return None
    value = float(costs[index])
    return value if np.isfinite(value) else None


__all__ = [
    "CycleScene",
    "ForecastSettings",
    "PathView",
    "PersonForecast",
    "PlanView",
    "ScannerView",
    "SceneBuilder",
    "XYTScene",
    "candidate_colour",
    "circle_polygon",
    "clearance_m",
    "path_view",
    "plan_xyt",
]
