"""Step 1, the situation: every check a candidate must pass, against the forecast and the corridor.

Source: paper §3 step 3 (legs checked against the obstacles' x-y-t cylinders) and step 4 (the
path boundary), docs/design.md §2 (segment check, capped uncertainty cone, horizon past a near subgoal).

What the paper leaves open and we chose:
* Legs are checked with the true combined radius + safety margin (the shared
  :class:`~viapath.planning.base.Inflation`); via points are placed ``planning_margin_m`` further
  out, or chaining never finds a path. With a shield behind the planner (docs/design.md §7) via points and
  legs to the subgoal also keep the robot's braking envelope at their speed (:meth:`LegChecks.envelope_m`).
* Legs are checked up to ``horizon_s``. Past an intermediate subgoal the robot is assumed to carry
  on along the next segment; past the final goal nothing is checked (the mission ends there). A
  blocked intermediate subgoal is given up within the bypass distance (paper Fig. 3), so legs towards
  it need to be free only up to there.
* Static geometry (rows of the obstacles marked static, velocity 0) is checked over a leg's whole length,
  past the horizon (its forecast is certain), and keeps no braking envelope
  (:func:`viapath.planning.viapath.legs.first_contacts`).
* The corridor check covers whole legs, not only via points. A robot already outside the corridor
  may not go further out, but may come back (``corridor_tolerance_m``): the compiled corridor checks
  (:func:`viapath.planning.viapath.legs.legs_inside`, :func:`~viapath.planning.viapath.legs.goal_legs_inside_all`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from viapath.geometry import cross2
from viapath.observation import Obstacles
from viapath.options import Settings
from viapath.path import DesignatedPath, SubgoalPolicy, SubgoalTracker
from viapath.planning.base import Inflation, Situation
from viapath.planning.viapath import packing
from viapath.planning.viapath.shapes import NO_SHAPES, StaticShapes, static_shapes

# Closer to the path line than this the robot is on the path: the way back is the leg to the subgoal.
ON_PATH_M = 0.01


class _CompiledInputs:
    """The checks' facts packed as the compiled steps take them (C-contiguous float64, made once per checks: a
    :class:`LegChecks` is not changed after it is built; dataclasses.replace makes a new one, without these)."""

    path: DesignatedPath
    position: np.ndarray
    heading_rad: float
    speed_mps: float
    turn_rate_radps: float
    obstacles: Obstacles
    check_radii: np.ndarray
    growth: np.ndarray
    growth_until_s: np.ndarray
    via_radii: np.ndarray
    continuation: tuple[np.ndarray, float] | None
    envelope_accel_mps2: float
    envelope_period_s: float
    max_accel_mps2: float

    def packed_obstacles(self) -> tuple[np.ndarray, ...]:
        """positions, velocities, check radii, growth, growth_until_s of the obstacles, for the compiled code."""
        cached = self.__dict__.get("_packed_obstacles")
        if cached is None:
            obstacles = self.obstacles
            n = len(obstacles.positions)
            cached = self.__dict__["_packed_obstacles"] = (
                _contiguous(obstacles.positions, (n, 2)),
                _contiguous(obstacles.velocities, (n, 2)),
                _contiguous(self.check_radii, (n,)),
                _contiguous(self.growth, (n,)),
                _contiguous(self.growth_until_s, (n,)),
            )
        return cached

    def packed_choice_inputs(self) -> tuple[Any, ...]:
        """What the compiled choice takes of this cycle (:func:`viapath.planning.viapath.selection.choose`'s order): the robot
        (:meth:`packed_robot`), the obstacles (:meth:`packed_obstacles`), the via radii, the ids, the
        continuation, the envelope, and the path's segment arrays and waypoints. Built in one go, every cycle:
        the path's arrays, continuations and envelopes are kept on the path (a path is not changed after it is
        built)."""
        cached = self.__dict__.get("_packed_choice_inputs")
        if cached is not None:
            return cached
        path = self.path
        kept: Any = path.__dict__.get("_packed_choice_arrays")
        if kept is None:
            kept = path.__dict__["_packed_choice_arrays"] = (
                tuple(
                    _contiguous(a, np.shape(a))
                    for a in (
                        path.segment_starts,
                        path.segment_directions,
                        path.segment_lengths_m,
                        path.half_widths_m,
                        path.waypoints,
                    )
                ),
                {},
                {},
            )
        episode, continuations, envelopes = kept
        continuation = self.continuation
        key = None if continuation is None else (*continuation[0].tolist(), float(continuation[1]))
        packed_continuation = continuations.get(key)
        if packed_continuation is None:
            packed_continuation = continuations[key] = self.packed_continuation()
        key = (self.envelope_accel_mps2, self.envelope_period_s, self.max_accel_mps2)
        envelope = envelopes.get(key)
        if envelope is None:
            envelope = envelopes[key] = self.packed_envelope()
        n = len(self.obstacles)
        ids = self.obstacles.ids
        if not (type(ids) is np.ndarray and ids.dtype == np.int64 and ids.flags.c_contiguous):
            ids = np.ascontiguousarray(ids, dtype=np.int64)
        cached = self.__dict__["_packed_choice_inputs"] = (
            self.packed_robot(),
            *self.packed_obstacles(),
            _contiguous(self.via_radii, (n,)),
            ids,
            packed_continuation,
            envelope,
            *episode,
        )
        return cached

    def packed_robot(self) -> np.ndarray:
        """(x, y, heading, speed, turn rate) of the robot."""
        cached = self.__dict__.get("_packed_robot")
        if cached is None:
            cached = self.__dict__["_packed_robot"] = np.array(
                [self.position[0], self.position[1], self.heading_rad, self.speed_mps, self.turn_rate_radps],
                dtype=np.float64,
            )
        return cached

    def packed_continuation(self) -> np.ndarray:
        """(dx, dy, length) of the segment after the subgoal, or an empty array (none)."""
        cached = self.__dict__.get("_packed_continuation")
        if cached is None:
            if self.continuation is None:
                cached = np.zeros(0)
            else:
                direction, length = self.continuation
                cached = np.array([direction[0], direction[1], length], dtype=np.float64)
            self.__dict__["_packed_continuation"] = cached
        return cached

    def packed_envelope(self) -> np.ndarray:
        """(person accel, period, robot accel) of the braking envelope; accel 0: none (:meth:`envelope_m`)."""
        cached = self.__dict__.get("_packed_envelope")
        if cached is None:
            cached = np.array([self.envelope_accel_mps2, self.envelope_period_s, self.max_accel_mps2], dtype=np.float64)
            self.__dict__["_packed_envelope"] = cached
        return cached


@dataclass
class LegChecks(_CompiledInputs):
    """One cycle's checks, vectorised over legs and obstacles."""

    path: DesignatedPath
    position: np.ndarray
    heading_rad: float
    speed_mps: float
    turn_rate_radps: float
    subgoal: np.ndarray
    subgoal_index: int
    is_final_subgoal: bool
    obstacles: Obstacles
    check_radii: np.ndarray  # robot + obstacle + margin + k·σ_position
    growth: np.ndarray  # k·σ_velocity
    growth_until_s: np.ndarray
    via_radii: np.ndarray  # check_radii + planning margin
    horizon_s: float
    stop_short_m: float  # legs to a blocked subgoal need be free only up to the bypass distance
    continuation: tuple[np.ndarray, float] | None  # direction and length of the segment after the subgoal
    corridor_tolerance_m: float
    corridor_check_spacing_m: float
    # With a shield behind the planner: via points and the legs to the subgoal keep the robot's braking
    # envelope from a person too, (person_accel / 2)·(period + v / max_accel)² at their speed v, so the
    # pass they offer is one the shield admits all along. (A leg back to the path that passes a walker
    # closer than that leaves the robot alongside and a little behind, where every forward command
    # moves towards the walker closer than it can stop: it creeps at the walker's speed.) Other legs
    # (side steps, slow legs, the escape) keep the plain radii: stepping aside needs every centimetre.
    # Keeping it from people walking the leg's way only (the creeping case) was tried: 93.0 % success
    # on mixed (seed 0) against 95.0 % for everyone, more contacts in crowds.
    envelope_accel_mps2: float = 0.0
    envelope_period_s: float = 0.0
    max_accel_mps2: float = 1.0

    def envelope_m(self, speeds: np.ndarray) -> np.ndarray:
        """How much further out a via point at ``speeds`` must lie for the robot to stop in time."""
        if self.envelope_accel_mps2 <= 0:
            return np.zeros(np.shape(speeds))
        stop_s = self.envelope_period_s + np.asarray(speeds) / self.max_accel_mps2
        return 0.5 * self.envelope_accel_mps2 * stop_s**2

    @classmethod
    def of(
        cls,
        situation: Situation,
        config: Settings,
        tracker: SubgoalTracker,
        policy: SubgoalPolicy,
        robot_radius_m: float,
    ) -> LegChecks:
        robot, path, obstacles, inflation = situation.robot, tracker.path, situation.obstacles, situation.inflation
        final = tracker.is_final
        blocked = not final and tracker.is_blocked(obstacles.positions, obstacles.radii_m, robot_radius_m)
        index = situation.subgoal_index
        continuation = None if (final or blocked) else (path.segment_directions[index], path.segment_lengths_m[index])
        return cls(
            path=path,
            position=situation.position,
            heading_rad=robot.heading_rad,
            speed_mps=float(robot.speed_mps),
            turn_rate_radps=float(robot.turn_rate_radps),
            subgoal=situation.subgoal,
            subgoal_index=index,
            is_final_subgoal=final,
            obstacles=obstacles,
            check_radii=inflation.check_radii,
            growth=inflation.growth,
            growth_until_s=inflation.growth_until_s,
            via_radii=inflation.check_radii + config.planning_margin_m,
            horizon_s=config.horizon_s,
            stop_short_m=policy.bypass_distance_m if blocked else 0.0,
            continuation=continuation,
            corridor_tolerance_m=situation.corridor_tolerance_m,
            corridor_check_spacing_m=config.corridor_check_spacing_m,
        )

    def with_less_inflation(
        self, fraction: float, robot_radius_m: float, settings: Mapping[str, Any], cap_too: bool = False
    ) -> LegChecks:
        """The same checks with ``fraction`` of the obstacles' uncertainty inflation (σ terms; with
        ``cap_too`` the cap on the cone's growth as well)."""
        obstacles = self.obstacles
        less = replace(
            obstacles,
            position_sigma_m=fraction * obstacles.position_sigma_m,
            velocity_sigma_mps=fraction * obstacles.velocity_sigma_mps,
        )
        if cap_too:
            settings = {**settings, "max_inflation_m": fraction * settings["max_inflation_m"]}
        inflation = Inflation.of(less, robot_radius_m, settings)
        return replace(
            self,
            obstacles=less,
            check_radii=inflation.check_radii,
            growth=inflation.growth,
            growth_until_s=inflation.growth_until_s,
            via_radii=inflation.check_radii + settings["planning_margin_m"],
        )

    def back_to_path(self, lookahead_m: float) -> LegChecks | None:
        """The same checks towards the path point ``lookahead_m`` ahead of the robot on the segment that
        ends at the subgoal, continued along the path to the subgoal (option ``return_lookahead_m``).
        None when the robot is on the path line or that point would lie at or past the subgoal: then
        the leg to the subgoal is the way back already."""
        segment = self.subgoal_index - 1
        path = self.path
        start, direction = path.segment_starts[segment], path.segment_directions[segment]
        length = float(path.segment_lengths_m[segment])
        relative = self.position - start
        if abs(float(cross2(direction, relative))) <= ON_PATH_M:  # on the path line (most cycles: asked first)
            return None
        ahead_m = max(float(relative @ direction), 0.0) + lookahead_m
        if ahead_m >= length:
            return None
        # The continuation to the subgoal is checked with the full radii, so a person standing on a
        # blocked subgoal blocks the way back too and the planner plans as the paper does.
        return replace(
            self, subgoal=start + ahead_m * direction, continuation=(direction, length - ahead_m), stop_short_m=0.0
        )

    # -- against the forecast ----------------------------------------------------------------------

    def contact_times(
        self,
        starts: np.ndarray,
        start_times: np.ndarray,
        velocities: np.ndarray,
        durations: np.ndarray,
        horizon_s: float | None = None,
        keep_envelope: bool = False,
    ) -> np.ndarray:
        """(K, N) first contact of each leg with each obstacle, up to the horizon (static geometry over the whole
        leg, :func:`viapath.planning.viapath.legs.first_contacts`); inf = free. With ``keep_envelope`` (and a
        shield behind the planner) each leg also keeps its braking envelope from people."""
        if len(self.obstacles) == 0:
            return np.full((len(starts), 0), np.inf)
        horizon_s = self.horizon_s if horizon_s is None else horizon_s
        checked = np.minimum(np.maximum(horizon_s - start_times, 0.0), durations)  # np.clip, without its dispatch
        envelope = None
        if keep_envelope and self.envelope_accel_mps2 > 0:
            envelope = self.envelope_m(np.hypot(velocities[:, 0], velocities[:, 1]))
        return packing.first_contacts(
            starts, start_times, velocities, checked, durations, self.packed_obstacles(), envelope, self.static_shapes()
        )

    def static_shapes(self) -> StaticShapes:
        """The static shapes of the obstacles, as the compiled steps take them (made once per checks)."""
        cached = self.__dict__.get("_static_shapes")
        if cached is None:
            obstacles = self.obstacles
            cached = self.__dict__["_static_shapes"] = (
                NO_SHAPES if obstacles.static_mask is None else static_shapes(obstacles.static_mask, obstacles.ids)
            )
        return cached

    def legs_free(
        self, starts: np.ndarray, start_times: np.ndarray, velocities: np.ndarray, durations: np.ndarray
    ) -> np.ndarray:
        return np.isinf(self.contact_times(starts, start_times, velocities, durations)).all(axis=1)

    def goal_legs(
        self, starts: np.ndarray, start_times: np.ndarray, speeds: np.ndarray, horizon_s: float | None = None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Straight legs from nodes to the subgoal: (directions, lengths, free (K,), contact (K, N)), in one
        compiled call (:func:`viapath.planning.viapath.legs.goal_legs`; static rows checked past the horizon
        without the braking envelope)."""
        return packing.goal_legs(self, starts, start_times, speeds, self.horizon_s if horizon_s is None else horizon_s)

    # -- the compiled steps the recipe calls -------------------------------------------------------

    # -- against the corridor (paper step 4) ---------------------------------------------------------

    def inside(self, points: np.ndarray) -> np.ndarray:
        """Which points are inside the corridor (or no further out than the robot is now)."""
        return self.path.corridor_excess(points) <= self.corridor_tolerance_m

    def legs_inside(self, starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
        return packing.legs_inside(self.path, starts, ends, self.corridor_check_spacing_m, self.corridor_tolerance_m)


_FLOAT64 = np.dtype(np.float64)  # (an identity test first: numpy's float64 arrays share this descriptor ...


def _contiguous(values: Any, shape: tuple[int, ...]) -> np.ndarray:
    """``values`` as a C-contiguous float64 array of ``shape`` (a scalar or a row is repeated)."""
    # ... the arrays compiled code hands back (the inflation's rows) may carry an equal descriptor of their own
    if (
        type(values) is np.ndarray
        and ((dtype := values.dtype) is _FLOAT64 or dtype == _FLOAT64)
        and values.shape == shape
        and values.flags.c_contiguous
    ):
        return values  # what the conversions below return for it, without them (every cycle, every array)
    array = np.asarray(values, dtype=np.float64)
    if array.shape != shape:
        array = np.broadcast_to(array, shape)
    return np.ascontiguousarray(array)
