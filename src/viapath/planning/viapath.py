"""The paper's planner: variable-speed via-point search in x-y-t, inside the path boundary.

Source: Yamada, Sa, Ohya, §3 (procedure steps 1-5, Eq. 1), after Tsubouchi et al.; DESIGN §2.

Procedure, per planning cycle (10 Hz):
1. If the straight leg to the current subgoal at the nominal speed is collision-free over the
   horizon, it is the plan (paper step 1).
2. Otherwise, for every speed in the set plus the current speed, build a tree of (position, time)
   nodes: the root is the robot; from each node try the straight leg to the subgoal; where it hits
   an obstacle, branch to the via points (avoiding line ∩ reachable cone) of that obstacle, on both
   sides and, when the obstacle is faster, both roots (pass early / let it overtake). At the root we
   branch on every obstacle the straight leg hits, deeper only on the first one hit (Tsubouchi's
   iterated forecast and planning). Depth is bounded by ``max_depth``.
3. Every leg is checked against every obstacle (constant-velocity forecast, radius growing with the
   velocity uncertainty) up to the horizon; a leg that leaves the corridor drops its branch
   (paper step 4, extended from via points to whole legs).
4. Complete candidates are ranked by E = k1·Dist + k2·Time + k3·|v - v_nominal| + k4·θ (Eq. 1).
5. The cheapest candidate the robot can follow within its motion limits is the plan: one whose
   first leg needs a sharp turn or a large speed change is rolled forward with the controller
   (arcs and lines) and dropped if the roll-out touches an obstacle or leaves the corridor.

What the paper leaves open and we chose (see DESIGN §2 pitfalls):
* Via points are computed on a disc grown by ``planning_margin_m``; legs are checked with the true
  combined radius (+ ``safety_margin_m``), or chaining never finds a path.
* Legs are checked up to ``horizon_s``. Past an intermediate subgoal the robot is assumed to carry on
  along the next segment; past the final goal nothing is checked (the mission ends there).
* Near-ties (the head-on case is exactly symmetric, and noise breaks it at random) go to
  ``preferred_side``: the other side pays ``side_tolerance``. The previous cycle's way round (same
  obstacle, side, early/late) gets a bonus of ``hysteresis`` so that near-equal options do not
  alternate. If that way has vanished, it is searched for once more with a fraction of the
  uncertainty inflation and kept if still cheaper (``keep_previous_way``): under noise a way
  often looks blocked for a single cycle, and the plan then flips and flips back.
* Under velocity uncertainty an obstacle grows into a cone (``uncertainty_sigmas`` σ_v per second),
  capped at ``max_inflation_m``: replanning every cycle corrects a velocity error long before it
  matters ten seconds ahead, and an uncapped cone makes any head-on pass wider than a corridor.
* Besides via points, candidates may first stand still or drive slower than nominal along the
  straight leg for a while (``slow_times_s``), then go on: letting a crossing person pass is then a
  straight candidate, not a sharp turn behind them. The speed term of Eq. 1 is time-weighted.
* A robot whose straight leg to the subgoal would cut a corner of the corridor (pushed back, or a
  blocked subgoal given up) goes back along the path: the path's corners become via points.
* θ is in radians by default; degrees make the θ term swamp the others.
* With no collision-free candidate: stop if standing still is safe over the horizon; otherwise take
  the drive command (v, ω), rolled out for ``escape_s`` within the limits, that stays in the
  corridor, gets out of any overlap and has the longest time to contact.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from viapath.geometry import LEFT, RIGHT, legs_first_contact, tangent_vectors, via_times, wrap_angle
from viapath.kinematics import UnicycleState, rollout, track
from viapath.observation import Command, Observation, Obstacles
from viapath.planning.base import Decision, Plan, Planner


@dataclass(frozen=True)
class Weights:
    """Weights of Eq. (1); paper values from its §4.2."""

    k1: float = 0.1  # per metre of path
    k2: float = 0.001  # per second of travel
    k3: float = 0.08  # per m/s away from the nominal speed
    k4: float = 0.3  # per radian (or degree) between heading and first leg


@dataclass
class ViaPathConfig:
    speeds_mps: tuple[float, ...] = (0.1, 0.2, 0.3, 0.4, 0.5)
    weights: Weights = field(default_factory=Weights)
    theta_unit: str = "rad"  # "rad" or "deg"
    planning_margin_m: float = 0.1
    safety_margin_m: float = 0.05
    horizon_s: float = 10.0
    max_depth: int = 3
    preferred_side: str = "left"
    hysteresis: float = 0.05
    uncertainty_sigmas: float = 2.0
    max_inflation_m: float = 0.15
    side_tolerance: float = 0.03
    slow_times_s: tuple[float, ...] = (0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 5.0, 6.0)
    rollout_heading_rad: float = 0.35  # roll a plan out when its first leg turns more than this
    rollout_s: float = 2.0
    turn_in_place_min_rad: float = 0.02  # a plan whose roll-out leaves the corridor turns on the spot first
    rollout_dt_s: float = 0.1
    keep_previous_way: bool = True  # constraint hysteresis, see ViaPathPlanner._keep_previous_way
    keep_previous_inflation: float = 0.25  # ... re-checked with this fraction of the uncertainty inflation
    max_rollouts: int = 8  # candidates tried, cheapest first, before falling back
    escape_s: float = 3.0  # how long each escape command is rolled out
    escape_dt_s: float = 0.1
    max_root_obstacles: int = 12
    heading_gain: float = 2.5
    corridor_check_spacing_m: float = 0.05
    record_candidates: bool = False  # keep every candidate's polyline in the plan (for display)

    def __post_init__(self) -> None:
        if self.theta_unit not in ("rad", "deg"):
            raise ValueError("theta_unit must be 'rad' or 'deg'")
        if self.preferred_side not in ("left", "right"):
            raise ValueError("preferred_side must be 'left' or 'right'")
        speeds = np.asarray(self.speeds_mps, dtype=float)
        if speeds.size == 0 or not np.all(np.isfinite(speeds)) or np.any(speeds <= 0):
            raise ValueError("speeds_mps must be a non-empty set of positive speeds")
        if self.max_depth < 1:
            raise ValueError("max_depth must be at least 1")


@dataclass
class _Nodes:
    """Growable arrays of search nodes: where and when the robot is, at which speed, how it got there."""

    position: list = field(default_factory=list)
    time_s: list = field(default_factory=list)
    speed: list = field(default_factory=list)
    parent: list = field(default_factory=list)
    length_m: list = field(default_factory=list)
    first_direction: list = field(default_factory=list)
    key: list = field(default_factory=list)  # (speed index, obstacle id, side, root) of the first branch
    slow_s: list = field(default_factory=list)  # how long the candidate first drives slower (or stands)
    slow_speed: list = field(default_factory=list)  # and at which speed

    def extend(self, **columns) -> np.ndarray:
        start = sum(len(p) for p in self.position)
        count = len(columns["position"])
        for name, value in columns.items():
            getattr(self, name).append(value)
        return np.arange(start, start + count)

    def stacked(self) -> dict[str, np.ndarray]:
        return {name: np.concatenate(getattr(self, name)) for name in self.__dataclass_fields__}


class ViaPathPlanner(Planner, name="viapath"):
    """Yamada-Sa-Ohya planner: follows the designated path, avoids by changing speed and direction."""

    def __init__(self, path, *, config: ViaPathConfig | None = None, **kwargs):
        super().__init__(path, **kwargs)
        self.config = config or ViaPathConfig()
        self._previous_key: tuple | None = None

    def reset(self) -> None:
        super().reset()
        self._previous_key = None

    @classmethod
    def options_from_spec(cls, spec) -> dict:
        """Planner options from a scenario's ``planner:`` block (any object with those attributes)."""
        config = ViaPathConfig(
            speeds_mps=tuple(spec.speeds),
            weights=Weights(**dict(spec.weights)),
            theta_unit=spec.theta_unit,
            planning_margin_m=spec.planning_margin_m,
            safety_margin_m=spec.safety_margin_m,
            horizon_s=spec.horizon_s,
            max_depth=spec.max_depth,
            preferred_side=spec.preferred_side,
            hysteresis=spec.hysteresis,
            uncertainty_sigmas=spec.uncertainty_sigmas,
            max_inflation_m=spec.max_inflation_m,
            side_tolerance=spec.side_tolerance,
            **spec.params,
        )
        return {"config": config}

    # -- the cycle -------------------------------------------------------------------------------

    def plan(self, observation: Observation) -> Decision:
        robot = observation.robot
        position = np.asarray(robot.position, dtype=float)
        obstacles = observation.obstacles.finite()
        radii = obstacles.radii_m + self.robot_radius_m
        self.subgoals.update(position, self.robot_radius_m, obstacles.positions, obstacles.radii_m)
        subgoal = self.subgoals.subgoal
        if self.subgoals.goal_reached(position):
            plan = Plan("goal", 0.0, subgoal.copy(), subgoal_index=self.subgoals.index)
            return Decision(Command.stop(), plan)

        search = _Search(self, position, robot.heading_rad, subgoal, obstacles, radii,
                         robot.speed_mps, robot.turn_rate_radps)
        speeds, nominal_index = self._speed_set(robot.speed_mps)
        result = search.run(speeds, nominal_index, self._previous_key)
        if result is None:
            return self._fallback(observation, search)
        if self.config.keep_previous_way and self._previous_key is not None:
            result = self._keep_previous_way(result, search, speeds, nominal_index)
        chosen, plan = result
        self._previous_key = chosen
        command = self.steer(observation, plan.target, plan.speed_mps, self.config.heading_gain)
        if plan.extras.get("turn_in_place"):
            command = Command(0.0, command.turn_rate_radps if command.turn_rate_radps else self._turn_towards(
                observation, plan.target))
        return Decision(command, plan)

    def _keep_previous_way(self, result, search: "_Search", speeds, nominal_index):
        """Hysteresis on the constraint as well as on the cost. Under velocity noise last cycle's way
        round often looks blocked for one cycle only because its inflation grew with the estimate's
        error; the plan then flips and flips back. If last cycle's way is gone, look for it again
        with ``keep_previous_inflation`` of the uncertainty inflation (the safety margin stays) and
        keep it if, with the usual hysteresis, it still costs less than the new choice."""
        chosen, plan = result
        previous = self._previous_key
        if plan.chosen is None or not len(plan.candidate_costs):
            return result  # a free straight leg at nominal speed (the paper's first choice)
        if _same_way(search.candidate_keys, previous).any():
            return result  # the previous way is still there: chosen again, or a fair switch on cost
        obstacles = search.obstacles
        if not (np.any(obstacles.position_sigma_m) or np.any(obstacles.velocity_sigma_mps)):
            return result  # no inflation to relax: the search would be the same
        kept = search.with_less_inflation(self.config.keep_previous_inflation).run(
            speeds, nominal_index, previous, only_way=previous)
        if kept is None or kept[1].chosen is None:
            return result
        kept_cost = kept[1].candidate_costs[kept[1].chosen]
        if kept_cost < plan.candidate_costs[plan.chosen]:
            kept[1].extras["kept_previous_way"] = True
            return kept
        return result

    def _turn_towards(self, observation: Observation, target) -> float:
        robot = observation.robot
        offset = np.asarray(target) - robot.position
        error = float(wrap_angle(np.arctan2(offset[1], offset[0]) - robot.heading_rad))
        return float(np.clip(self.config.heading_gain * error, -self.limits.max_turn_rate_radps,
                             self.limits.max_turn_rate_radps))

    def nominal_in_speed_set_mps(self) -> float:
        return round(min(self.nominal_speed_mps, self.limits.max_speed_mps), 3)

    def _speed_set(self, current_speed_mps: float) -> tuple[np.ndarray, int]:
        """The configured speeds, the current speed and the nominal speed (mm/s resolution, within
        the limit), sorted; and where the nominal speed is in it."""
        top = self.limits.max_speed_mps
        nominal = self.nominal_in_speed_set_mps()
        speeds = {round(min(v, top), 3) for v in self.config.speeds_mps} | {nominal}
        if current_speed_mps > 0.02:
            speeds.add(round(min(current_speed_mps, top), 3))
        ordered = sorted(speeds)
        return np.array(ordered), ordered.index(nominal)

    # -- no collision-free candidate -------------------------------------------------------------

    def _fallback(self, observation: Observation, search: "_Search") -> Decision:
        robot = observation.robot
        position = np.asarray(robot.position, dtype=float)
        base = dict(subgoal_index=self.subgoals.index)
        self._previous_key = None
        standing = search.contact_times(position[None], np.zeros(1), np.zeros((1, 2)), np.array([self.config.horizon_s]))
        if np.isinf(standing).all():
            return Decision(Command.stop(), Plan("stop", 0.0, position.copy(), **base))
        # Even standing still is hit: of a fan of drive commands (arcs within the limits, and
        # standing), take the one that stays in the corridor, gets out of any overlap and puts
        # contact off the longest.
        commands, ends, score = self._escape_scores(robot, search)
        best = int(np.argmax(score))
        speed, turn = (float(value) for value in commands[best])
        return Decision(Command(speed, turn), Plan("escape", speed, ends[best], **base))

    def _escape_scores(self, robot, search: "_Search"):
        """Commands (v, ω), where each leaves the robot, and the score of each (higher is better).

        Each command is held for ``escape_s`` and rolled out with the drive's limits. In order of
        importance: out of any overlap by the end and never deeper in on the way; no contact at all
        during the roll-out; never further out of the corridor than now (worth up to 2 s of time to
        contact: when stopping is not safe, not being hit comes first); the longest time to
        contact; then progress towards the subgoal, and slower rather than sideways.
        """
        config, limits = self.config, self.limits
        position = np.asarray(robot.position, dtype=float)
        speeds = np.unique(np.concatenate([[0.0], config.speeds_mps, [limits.max_speed_mps]]))
        turns = np.linspace(-limits.max_turn_rate_radps, limits.max_turn_rate_radps, 9)
        commands = np.stack([grid.ravel() for grid in np.meshgrid(speeds, turns)], axis=1)
        dt = config.escape_dt_s
        steps = max(1, int(round(config.escape_s / dt)))
        state = UnicycleState(float(position[0]), float(position[1]), float(robot.heading_rad),
                              float(robot.speed_mps), float(robot.turn_rate_radps))
        positions = rollout(state, commands, limits, dt, steps)  # (K, S, 2)
        times = dt * np.arange(1, steps + 1)

        allowed = search.corridor_tolerance
        excess = self.path.corridor_excess(positions.reshape(-1, 2)).reshape(len(commands), steps)
        inside = np.all(excess <= allowed, axis=1)

        # Only people who could come within reach during the roll-out matter (triangle inequality:
        # the robot travels at most `travel`, each person |v|·T, each cone grows at most so much).
        horizon = steps * dt
        travel = float(np.max(np.hypot(*(positions - position).reshape(-1, 2).T)))
        obstacles = search.obstacles
        gap_all = np.hypot(*(position - obstacles.positions).T) - search.check_radii
        growth_all = search.growth * np.minimum(horizon, search.growth_until_s)
        near = gap_all - growth_all - np.hypot(*obstacles.velocities.T) * horizon - travel <= 0
        positions_obs, velocities_obs = obstacles.positions[near], obstacles.velocities[near]
        centres = positions_obs[None] + velocities_obs[None] * times[:, None, None]  # (S, N, 2)
        reach = search.check_radii[near] + search.growth[near] * np.minimum(times[:, None], search.growth_until_s[near])
        offset = positions[:, :, None, :] - centres[None]
        gap = np.hypot(offset[..., 0], offset[..., 1]) - reach[None]  # (K, S, N)
        gap_now = gap_all[near]
        overlapping = gap_now <= 0
        touching = (gap < 0) & ~overlapping
        first = np.where(touching.any(axis=1), np.argmax(touching, axis=1), steps)  # (K, N)
        time_to_contact = np.min(first, axis=1, initial=steps) * dt
        if overlapping.any():
            deeper = np.min(gap[..., overlapping], axis=1) - gap_now[overlapping]
            still_inside = gap[:, -1, overlapping]
            separation = np.sum(np.minimum(deeper, 0.0) + np.minimum(still_inside, 0.0), axis=1)
        else:
            separation = np.zeros(len(commands))
        toward = search.subgoal - position
        toward = toward / max(float(np.hypot(*toward)), 1e-9)
        progress = (positions[:, -1] - position) @ toward / config.escape_s
        free = time_to_contact >= steps * dt
        # When contact cannot be avoided, fleeing fast mostly runs into someone else: a contact at
        # speed counts 0.5 s of time to contact per m/s against the command (a tie-break, no more:
        # the longest time to contact still decides, as the paper asks).
        score = (1e2 * separation + 20.0 * free + 2.0 * inside + time_to_contact
                 - np.where(free, 0.005, 0.5) * commands[:, 0] + 0.01 * progress)
        return commands, positions[:, -1], score


class _Search:
    """One cycle's x-y-t search, vectorised over nodes and obstacles."""

    def __init__(self, planner: ViaPathPlanner, position, heading_rad, subgoal, obstacles: Obstacles, radii,
                 speed_mps: float = 0.0, turn_rate_radps: float = 0.0):
        config = planner.config
        self.speed_mps = float(speed_mps)
        self.turn_rate_radps = float(turn_rate_radps)
        self.planner = planner
        self.config = config
        self.path = planner.path
        self.position = position
        self.heading_rad = heading_rad
        self.subgoal = subgoal
        self.obstacles = obstacles
        k = config.uncertainty_sigmas
        self.check_radii = radii + config.safety_margin_m + k * obstacles.position_sigma_m
        self.growth = k * obstacles.velocity_sigma_mps
        # Replanning every cycle corrects a velocity error before it matters far ahead, so the cone
        # stops growing once it has added max_inflation_m (else head-on passes never fit a corridor).
        with np.errstate(divide="ignore", over="ignore"):
            self.growth_until_s = np.where(self.growth > 0, config.max_inflation_m / self.growth, np.inf)
        self.via_radii = self.check_radii + config.planning_margin_m
        self.horizon_s = config.horizon_s
        tracker = planner.subgoals
        # A blocked intermediate subgoal is given up once the robot is within the bypass distance
        # (paper Fig. 3), so legs towards it need to be free only up to there.
        blocked = tracker.is_blocked(obstacles.positions, obstacles.radii_m, planner.robot_radius_m)
        self.stop_short_m = planner.subgoal_policy.bypass_distance_m if blocked else 0.0
        # Beyond an intermediate subgoal the robot carries on along the next segment.
        index = tracker.index
        self.continuation = None if (tracker.is_final or blocked) else (
            planner.path.segment_directions[index], planner.path.segment_lengths_m[index])
        # A robot already outside the corridor may not go further out, but may come back.
        self.corridor_tolerance = max(0.0, float(self.path.corridor_excess(position))) + 1e-9
        self.subgoal_segments = [i for i in (index - 1, index) if i < len(planner.path.segment_lengths_m)]
        self.combined_radii = radii
        self.candidate_keys = np.zeros((0, 4), dtype=int)  # of the complete candidates, once run() ranked them

    def with_less_inflation(self, fraction: float) -> "_Search":
        """The same cycle's search with ``fraction`` of the obstacles' uncertainty inflation."""
        obstacles = self.obstacles
        less_inflated = replace(obstacles, position_sigma_m=fraction * obstacles.position_sigma_m,
                                velocity_sigma_mps=fraction * obstacles.velocity_sigma_mps)
        return _Search(self.planner, self.position, self.heading_rad, self.subgoal, less_inflated,
                       self.combined_radii, self.speed_mps, self.turn_rate_radps)

    # -- checks ----------------------------------------------------------------------------------

    def contact_times(self, starts, start_times, velocities, durations, horizon_s=None) -> np.ndarray:
        """(K, N) first contact of each leg with each obstacle, up to the horizon; inf = free."""
        if len(self.obstacles) == 0:
            return np.full((len(starts), 0), np.inf)
        horizon_s = self.horizon_s if horizon_s is None else horizon_s
        checked = np.clip(horizon_s - start_times, 0.0, durations)
        return legs_first_contact(starts, start_times, velocities, checked, self.obstacles.positions,
                                  self.obstacles.velocities, self.check_radii, self.growth,
                                  self.growth_until_s)

    def goal_legs(self, starts, start_times, speeds, horizon_s=None):
        """Straight legs from nodes to the subgoal: (directions, lengths, free (K,), contact (K, N))."""
        offset = self.subgoal - starts
        lengths = np.hypot(offset[:, 0], offset[:, 1])
        directions = offset / np.maximum(lengths, 1e-12)[:, None]
        durations = np.maximum(lengths - self.stop_short_m, 0.0) / speeds
        velocities = directions * speeds[:, None]
        contact = self.contact_times(starts, start_times, velocities, durations, horizon_s)
        if self.continuation is not None and contact.shape[1]:
            direction, length = self.continuation
            more = self.contact_times(np.broadcast_to(self.subgoal, starts.shape), start_times + durations,
                                      direction * speeds[:, None], length / speeds, horizon_s)
            contact = np.minimum(contact, more + durations[:, None])
        free = np.isinf(contact).all(axis=1) & self._goal_legs_inside(starts)
        return directions, lengths, free, contact

    def _goal_legs_inside(self, starts) -> np.ndarray:
        # The subgoal ends both capsules next to it; a leg from a point inside one of them is inside
        # that capsule (convex). Only other legs need the general check.
        path = self.path
        inside = np.zeros(len(starts), dtype=bool)
        for i in self.subgoal_segments:
            rel = starts - path.segment_starts[i]
            along = np.clip(rel @ path.segment_directions[i], 0.0, path.segment_lengths_m[i])
            gap = np.hypot(*(rel - along[:, None] * path.segment_directions[i]).T) - path.half_widths_m[i]
            inside |= gap <= self.corridor_tolerance
        if not inside.all():
            rest = np.flatnonzero(~inside)
            inside[rest] = path.legs_inside(starts[rest], np.broadcast_to(self.subgoal, (len(rest), 2)),
                                            self.config.corridor_check_spacing_m, self.corridor_tolerance)
        return inside

    # -- search ----------------------------------------------------------------------------------

    def run(self, speeds: np.ndarray, nominal_index: int, previous_key, only_way=None):
        """Best candidate as ``(key, plan)``, or None when no candidate is collision-free.
        With ``only_way`` (a key), only candidates going that way round are considered."""
        config = self.config
        nodes = _Nodes()
        n_speeds = len(speeds)
        frontier = nodes.extend(
            position=np.broadcast_to(self.position, (n_speeds, 2)), time_s=np.zeros(n_speeds), speed=speeds,
            parent=np.full(n_speeds, -1), length_m=np.zeros(n_speeds), first_direction=np.zeros((n_speeds, 2)),
            key=np.stack([np.arange(n_speeds), np.full(n_speeds, -1), np.zeros(n_speeds, int), np.zeros(n_speeds, int)], 1),
            slow_s=np.zeros(n_speeds), slow_speed=np.zeros(n_speeds),
        )
        data = nodes.stacked()
        complete, goal_length = [], []
        for depth in range(config.max_depth + 1):
            starts, times, node_speeds = data["position"][frontier], data["time_s"][frontier], data["speed"][frontier]
            directions, lengths, free, contact = self.goal_legs(starts, times, node_speeds)
            if depth == 0:
                if free[nominal_index] and only_way is None:
                    # Paper step 1: a free straight path at the normal speed is the plan, if the
                    # robot can turn onto it in time.
                    straight = self._straight_plan(speeds[nominal_index], nominal_index)
                    if self.can_follow(straight[1]):
                        return straight
                # A straight candidate's first leg is its goal leg.
                data["first_direction"][frontier] = directions
                nodes.first_direction[0] = directions
            complete.append(frontier[free])
            goal_length.append(lengths[free])
            if depth == 0 and config.slow_times_s and len(self.obstacles):
                slowing = self._slow_candidates(nodes, speeds)
                if slowing is not None:
                    complete.append(slowing[0])
                    goal_length.append(slowing[1])
                data = nodes.stacked()
            if depth == config.max_depth:
                break
            next_frontier = [self._corner_nodes(nodes, speeds)] if depth == 0 else []
            blocked = np.flatnonzero(~free & np.isfinite(contact).any(axis=1))
            if len(blocked) and len(self.obstacles):
                if depth == 0:
                    rows, pair_obstacles = self._root_pairs(contact[blocked])
                    pair_nodes = frontier[blocked][rows]
                else:
                    pair_nodes = frontier[blocked]
                    pair_obstacles = np.argmin(contact[blocked], axis=1)
                children = self._expand(data, pair_nodes, pair_obstacles, is_root=(depth == 0))
                if children is not None:
                    next_frontier.append(nodes.extend(**children))
            frontier = np.concatenate([np.zeros(0, int)] + next_frontier)
            if len(frontier) == 0:
                break
            data = nodes.stacked()

        complete = np.concatenate(complete)
        if len(complete) == 0:
            return None
        total_length = data["length_m"][complete] + np.concatenate(goal_length)
        speeds_c = data["speed"][complete]
        slow_s, slow_speed = data["slow_s"][complete], data["slow_speed"][complete]
        driven_s = (total_length - slow_speed * slow_s) / speeds_c
        travel_time = slow_s + driven_s
        # Eq. 1's speed term, time-weighted over a candidate that first slows down or waits.
        nominal = self.planner.nominal_speed_mps
        speed_error = (slow_s * np.abs(slow_speed - nominal) + driven_s * np.abs(speeds_c - nominal)) / travel_time
        first = data["first_direction"][complete]
        theta = np.abs(wrap_angle(np.arctan2(first[:, 1], first[:, 0]) - self.heading_rad))
        if config.theta_unit == "deg":
            theta = np.degrees(theta)
        weights = config.weights
        cost = (weights.k1 * total_length + weights.k2 * travel_time
                + weights.k3 * speed_error + weights.k4 * theta)
        keys = np.column_stack([np.round(speeds_c * 1000).astype(int), data["key"][complete, 1:]])
        self.candidate_keys = keys
        preferred = LEFT if config.preferred_side == "left" else RIGHT
        cost = cost + config.side_tolerance * ((keys[:, 2] != 0) & (keys[:, 2] != preferred))
        if previous_key is not None:
            # Keep last cycle's way round (same obstacle, side, early/late), and its speed.
            same_way = _same_way(keys, previous_key)
            same_speed = keys[:, 0] == previous_key[0]
            cost = cost - config.hysteresis * (same_way + 0.5 * (same_way & same_speed))
        if only_way is not None:
            cost = np.where(_same_way(keys, only_way), cost, np.inf)
            if not np.isfinite(cost).any():
                return None
        polylines = [self._polyline(data, node) for node in complete] if config.record_candidates else []
        # The cheapest candidate whose first leg the robot can actually follow (motion limits).
        for best in np.argsort(cost, kind="stable")[:config.max_rollouts]:
            if not np.isfinite(cost[best]):
                break
            if slow_s[best] > 0:
                plan = self._slow_plan(data, complete, cost, best, polylines)
            else:
                plan = self._tree_plan(data, complete, cost, best, polylines, float(speeds_c[best]))
            if self.can_follow(plan):
                return keys[best], plan
        return None

    def _tree_plan(self, data, complete, cost, best, polylines, speed: float) -> Plan:
        chosen_line = self._polyline(data, complete[best])
        return Plan(
            status="avoid" if len(chosen_line) > 2 else "straight",
            speed_mps=speed,
            target=chosen_line[1].copy(),
            via_points=chosen_line[1:-1].copy(),
            waypoints=chosen_line,
            subgoal_index=self.planner.subgoals.index,
            candidate_count=len(complete),
            candidate_costs=cost,
            candidate_polylines=polylines,
            chosen=int(best),
        )

    # -- motion limits ---------------------------------------------------------------------------

    def can_follow(self, plan: Plan) -> bool:
        """Whether the robot, steering for the plan's target within its limits, keeps clear of every
        obstacle and inside the corridor. The x-y-t legs assume instant turns and speed changes; a
        plan that needs a sharp turn or a large speed change is rolled forward with the controller
        (arcs and lines, as the drive executes them) and dropped if that roll-out fails."""
        config, limits = self.config, self.planner.limits
        offset = plan.target - self.position
        heading_error = abs(float(wrap_angle(np.arctan2(offset[1], offset[0]) - self.heading_rad)))
        speed_change = abs(plan.speed_mps - self.speed_mps)
        if np.hypot(*offset) < 1e-6 or (heading_error <= config.rollout_heading_rad
                                          and speed_change <= limits.max_accel_mps2 * config.rollout_dt_s * 2):
            return True
        dt = config.rollout_dt_s
        steps = max(1, int(round(config.rollout_s / dt)))
        state = UnicycleState(float(self.position[0]), float(self.position[1]), float(self.heading_rad),
                              self.speed_mps, self.turn_rate_radps)
        path = track(state, plan.target, plan.speed_mps, limits, dt, steps, config.heading_gain)
        if not self._clear(path, dt):
            return False
        if np.all(self.path.corridor_excess(path) <= self.corridor_tolerance):
            return True
        # Turning while moving would swing out of the corridor: turn on the spot first, if standing
        # is safe meanwhile (the next cycles then find the robot facing its leg). Even a small turn:
        # at the corridor edge, or outside it after an escape, a robot facing a little outwards
        # would otherwise never get going again.
        turn_s = heading_error / limits.max_turn_rate_radps + 1.0
        standing = np.repeat(self.position[None], max(1, int(np.ceil(turn_s / dt))), axis=0)
        if heading_error > config.turn_in_place_min_rad and self._clear(standing, dt):
            plan.extras["turn_in_place"] = True
            return True
        return False

    def _clear(self, path: np.ndarray, dt: float) -> bool:
        """Whether robot positions ``path`` (one per ``dt`` from now) keep clear of every obstacle."""
        if len(self.obstacles) == 0:
            return True
        times = dt * np.arange(1, len(path) + 1)[:, None]
        obstacles = self.obstacles
        centres = obstacles.positions[None] + obstacles.velocities[None] * times[..., None]
        reach = self.check_radii + self.growth * np.minimum(times, self.growth_until_s)
        distance = np.hypot(*(path[:, None, :] - centres).transpose(2, 0, 1))
        # Already inside an obstacle's margin (a close pass): only forbid getting closer still.
        now = np.hypot(*(self.position - obstacles.positions).T)
        return bool(np.all(distance >= np.minimum(reach, now - 1e-3)))

    def _corner_nodes(self, nodes: _Nodes, speeds: np.ndarray) -> np.ndarray:
        """When the straight leg to the subgoal would cut a corner of the corridor (the robot was
        pushed back, or a blocked subgoal was given up), the path's own corners between the robot
        and the subgoal become via points: the way back along the designated path."""
        path, tracker = self.path, self.planner.subgoals
        segment = int(path.project(self.position)[0])
        corners = np.arange(segment + 1, tracker.index)
        if len(corners) == 0 or self._goal_legs_inside(self.position[None])[0]:
            return np.zeros(0, int)
        corner, speed = (grid.ravel() for grid in np.meshgrid(corners, speeds))
        targets = path.waypoints[corner]
        offset = targets - self.position
        length = np.hypot(offset[:, 0], offset[:, 1])
        direction = offset / np.maximum(length, 1e-12)[:, None]
        starts = np.broadcast_to(self.position, targets.shape)
        duration = length / speed
        good = np.isinf(self.contact_times(starts, np.zeros(len(speed)), direction * speed[:, None], duration)).all(axis=1)
        good &= path.legs_inside(starts, targets, self.config.corridor_check_spacing_m, self.corridor_tolerance)
        count = int(good.sum())
        if count == 0:
            return np.zeros(0, int)
        return nodes.extend(
            position=targets[good], time_s=duration[good], speed=speed[good],
            parent=np.searchsorted(speeds, speed[good]),  # the root node of that speed
            length_m=length[good], first_direction=direction[good],
            key=np.stack([np.searchsorted(speeds, speed[good]), np.full(count, _CORNER), np.zeros(count, int),
                          corner[good]], 1),
            slow_s=np.zeros(count), slow_speed=np.zeros(count),
        )

    def _slow_candidates(self, nodes: _Nodes, speeds: np.ndarray):
        """Stand still or drive slower than nominal towards the subgoal for each of
        ``slow_times_s``, then on at nominal speed or faster: the x-y-t way of letting an obstacle
        pass first.
        Returns (complete node indices, goal leg lengths) or None."""
        if not self._goal_legs_inside(self.position[None])[0]:
            return None  # slowing down runs along the straight leg, which would leave the corridor
        nominal = self.planner.nominal_in_speed_set_mps()
        slow_speeds = np.concatenate([[0.0], speeds[speeds < nominal - 1e-9]])
        duration, slow_speed = (grid.ravel() for grid in np.meshgrid(np.asarray(self.config.slow_times_s, float),
                                                                     slow_speeds))
        offset = self.subgoal - self.position
        direction = offset / max(float(np.hypot(*offset)), 1e-12)
        # Never past the subgoal while slowing down.
        ok = slow_speed * duration < np.hypot(*offset) - 1e-6
        duration, slow_speed = duration[ok], slow_speed[ok]
        starts = np.broadcast_to(self.position, (len(duration), 2))
        first_leg = self.contact_times(starts, np.zeros(len(duration)), direction * slow_speed[:, None], duration)
        free = np.isinf(first_leg).all(axis=1)
        if not free.any():
            return None
        duration, slow_speed = duration[free], slow_speed[free]
        # Then at least the nominal speed: waiting only makes sense when the way is clear afterwards
        # (slowing down for good is the straight candidates' job).
        after = speeds[speeds >= nominal - 1e-9]
        d, v_slow = np.repeat(duration, len(after)), np.repeat(slow_speed, len(after))
        v_after = np.tile(after, len(duration))
        ends = self.position + direction * (v_slow * d)[:, None]
        # The leg after slowing down is checked to its end, not to the horizon: waiting is for
        # letting someone pass, not for pushing a collision past the horizon cycle after cycle
        # (behind a slow walker that would wait for ever).
        _, lengths, free, _ = self.goal_legs(ends, d, v_after, np.inf)
        if not free.any():
            return None
        count = int(free.sum())
        speed_index = np.searchsorted(speeds, v_after[free])
        index = nodes.extend(
            position=ends[free], time_s=d[free], speed=v_after[free], parent=np.full(count, -1),
            length_m=(v_slow * d)[free], first_direction=np.broadcast_to(direction, (count, 2)).copy(),
            key=np.stack([speed_index, np.full(count, _SLOW), np.zeros(count, int), np.zeros(count, int)], 1),
            slow_s=d[free], slow_speed=v_slow[free],
        )
        return index, lengths[free]

    def _slow_plan(self, data, complete, cost, best, polylines) -> Plan:
        node = complete[best]
        speed = float(data["slow_speed"][node])
        line = np.array([self.position, self.subgoal])
        return Plan(
            status="wait" if speed == 0.0 else "slow", speed_mps=speed, target=self.subgoal.copy(), waypoints=line,
            subgoal_index=self.planner.subgoals.index, candidate_count=len(complete), candidate_costs=cost,
            candidate_polylines=polylines, chosen=int(best),
            extras={"slow_s": float(data["slow_s"][node]), "speed_after_mps": float(data["speed"][node])},
        )

    def _straight_plan(self, speed: float, speed_index: int):
        key = np.array([int(round(speed * 1000)), -1, 0, 0])
        plan = Plan("straight", float(speed), self.subgoal.copy(), waypoints=np.array([self.position, self.subgoal]),
                    subgoal_index=self.planner.subgoals.index, candidate_count=1, chosen=0)
        return key, plan

    def _root_pairs(self, contact: np.ndarray):
        """(row, obstacle) pairs to branch on at the root: each obstacle the leg hits, earliest first."""
        rows, cols = np.nonzero(np.isfinite(contact))
        limit = self.config.max_root_obstacles
        if limit and len(rows) > limit:
            order = np.lexsort((contact[rows, cols], rows))
            rows, cols = rows[order], cols[order]
            rank = np.arange(len(rows)) - np.searchsorted(rows, rows)
            keep = rank < limit
            rows, cols = rows[keep], cols[keep]
        return rows, cols

    def _expand(self, data, node_index, obstacle_index, is_root: bool):
        """Via-point children of each (node, obstacle) pair: both sides, both roots, legs checked."""
        starts = data["position"][node_index]
        times = data["time_s"][node_index]
        speeds = data["speed"][node_index]
        obstacles = self.obstacles
        velocity = obstacles.velocities[obstacle_index]
        centre_now = obstacles.positions[obstacle_index] + velocity * times[:, None]
        # The radius grows with prediction uncertainty; evaluate it near the expected passing time.
        reach_time = np.hypot(*(centre_now - starts).T) / speeds
        passing_time = np.minimum(times + reach_time, self.growth_until_s[obstacle_index])
        radius = self.via_radii[obstacle_index] + self.growth[obstacle_index] * passing_time
        # A node already closer than that (after passing on a previous leg) goes round tangentially.
        distance = np.hypot(*(centre_now - starts).T)
        radius = np.maximum(np.minimum(radius, 0.98 * distance), 0.0)

        # Axis 1 enumerates (side, root): (left, early), (right, early), (left, late), (right, late).
        w, valid = tangent_vectors(starts[:, None, :], centre_now[:, None, :], radius[:, None], _SIDES[None, :2])
        t_early, t_late = via_times(w, velocity[:, None, :], speeds[:, None])
        t_via = np.concatenate([t_early, t_late], axis=1)
        w = np.concatenate([w, w], axis=1)
        ok = np.broadcast_to(valid, t_early.shape)
        ok = np.concatenate([ok, ok], axis=1) & (t_via <= 3 * self.horizon_s)
        pair, option = np.nonzero(ok)
        if len(pair) == 0:
            return None
        t_k = t_via[pair, option]
        starts_k, times_k, speeds_k = starts[pair], times[pair], speeds[pair]
        leg_velocity = (w[pair, option] + velocity[pair] * t_k[:, None]) / t_k[:, None]
        via = starts_k + leg_velocity * t_k[:, None]
        good = np.isinf(self.contact_times(starts_k, times_k, leg_velocity, t_k)).all(axis=1)
        good[good] = self.path.legs_inside(starts_k[good], via[good], self.config.corridor_check_spacing_m,
                                           self.corridor_tolerance)
        if not good.any():
            return None
        pair, option, t_k = pair[good], option[good], t_k[good]
        parent = node_index[pair]
        if is_root:
            first_direction = leg_velocity[good] / speeds_k[good, None]
            key = np.stack([data["key"][parent, 0], obstacles.ids[obstacle_index[pair]],
                            _SIDES[option], _ROOTS[option]], axis=1)
        else:
            first_direction = data["first_direction"][parent]
            key = data["key"][parent]
        return dict(
            position=via[good], time_s=times_k[good] + t_k, speed=speeds_k[good], parent=parent,
            length_m=data["length_m"][parent] + speeds_k[good] * t_k,
            first_direction=first_direction, key=key, slow_s=np.zeros(int(good.sum())),
            slow_speed=np.zeros(int(good.sum())),
        )

    def _polyline(self, data, node: int) -> np.ndarray:
        points = [self.subgoal]
        while node >= 0:
            points.append(data["position"][node])
            node = int(data["parent"][node])
        return np.array(points[::-1])


def _same_way(keys: np.ndarray, key: np.ndarray) -> np.ndarray:
    """Which candidate keys go the same way round as ``key`` (obstacle, side, early/late), any speed."""
    return np.all(keys[:, 1:] == key[1:], axis=1)


_SIDES = np.array([LEFT, RIGHT, LEFT, RIGHT])
_SLOW = -2  # the "obstacle id" in the key of a candidate that slows down or waits first
_CORNER = -3  # ... and of one that goes back along the path through a corner (its index as 'root')
_ROOTS = np.array([0, 0, 1, 1])
