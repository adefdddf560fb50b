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

What the paper leaves open and we chose (see DESIGN §2 pitfalls):
* Via points are computed on a disc grown by ``planning_margin_m``; legs are checked with the true
  combined radius (+ ``safety_margin_m``), or chaining never finds a path.
* Legs are checked up to ``horizon_s``. Past an intermediate subgoal the robot is assumed to carry on
  along the next segment; past the final goal nothing is checked (the mission ends there).
* Ties (the head-on case is exactly symmetric) go to ``preferred_side``; the previous cycle's
  choice gets a bonus of ``hysteresis`` so that near-equal options do not alternate.
* θ is in radians by default; degrees make the θ term swamp the others.
* With no collision-free candidate: stop if standing still is safe over the horizon; otherwise take
  the motion with the longest time to contact (moving straight away when already touching).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from viapath.geometry import LEFT, RIGHT, legs_first_contact, tangent_vectors, via_times, wrap_angle
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
    safety_margin_m: float = 0.0
    horizon_s: float = 10.0
    max_depth: int = 3
    preferred_side: str = "left"
    hysteresis: float = 0.01
    uncertainty_sigmas: float = 2.0
    max_root_obstacles: int = 12
    heading_gain: float = 2.5
    corridor_check_spacing_m: float = 0.05

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

        search = _Search(self, position, robot.heading_rad, subgoal, obstacles, radii)
        nominal = min(self.nominal_speed_mps, self.limits.max_speed_mps)
        if search.straight_is_free(nominal):
            self._previous_key = ("straight", round(nominal, 3))
            plan = Plan("straight", nominal, subgoal.copy(), waypoints=np.array([position, subgoal]),
                        subgoal_index=self.subgoals.index, candidate_count=1)
            return Decision(self.steer(observation, subgoal, nominal, self.config.heading_gain), plan)

        speeds = self._speed_set(robot.speed_mps)
        result = search.run(speeds, self._previous_key)
        if result is None:
            return self._fallback(observation, search)
        chosen, plan = result
        self._previous_key = chosen
        return Decision(self.steer(observation, plan.target, plan.speed_mps, self.config.heading_gain), plan)

    def _speed_set(self, current_speed_mps: float) -> np.ndarray:
        speeds = list(self.config.speeds_mps)
        if current_speed_mps > 0.02:
            speeds.append(current_speed_mps)
        speeds = np.unique(np.round(np.clip(speeds, 0.0, self.limits.max_speed_mps), 3))
        return speeds[speeds > 0]

    # -- no collision-free candidate -------------------------------------------------------------

    def _fallback(self, observation: Observation, search: "_Search") -> Decision:
        robot = observation.robot
        position = np.asarray(robot.position, dtype=float)
        standing = search.contact_times(position[None], np.zeros(1), np.zeros((1, 2)), np.array([self.config.horizon_s]))
        base = dict(subgoal_index=self.subgoals.index)
        if np.isinf(standing).all():
            self._previous_key = ("stop",)
            return Decision(Command.stop(), Plan("stop", 0.0, position.copy(), **base))
        self._previous_key = None
        obstacles, radii = search.obstacles, search.check_radii
        gaps = np.hypot(*(obstacles.positions - position).T) - radii
        if gaps.min() <= 0:
            # Already touching: move straight away from the centre of the deepest overlap.
            worst = int(np.argmin(gaps))
            away = position - obstacles.positions[worst]
            target = position + away / max(np.hypot(*away), 1e-9)
            speed = self.limits.max_speed_mps
            command = self.steer(observation, target, speed, self.config.heading_gain)
            return Decision(command, Plan("escape", speed, target, **base))
        # Even standing still is hit: take the straight motion with the longest time to contact,
        # preferring to stay inside the corridor.
        headings = robot.heading_rad + np.linspace(-np.pi, np.pi, 24, endpoint=False)
        speeds = np.unique(np.concatenate([self.config.speeds_mps, [self.limits.max_speed_mps]]))
        h, v = np.meshgrid(headings, speeds)
        h, v = h.ravel(), v.ravel()
        velocities = np.stack([np.cos(h), np.sin(h)], axis=1) * v[:, None]
        horizon = np.full(len(h), self.config.horizon_s)
        contact = search.contact_times(np.repeat(position[None], len(h), 0), np.zeros(len(h)), velocities, horizon)
        time_to_contact = contact.min(axis=1)
        ends = position + velocities * np.minimum(time_to_contact, 2.0)[:, None]
        inside = self.path.contains(ends)
        score = np.where(inside, 0.0, -1e3) + np.minimum(time_to_contact, 1e3)
        best = int(np.argmax(score))
        target = position + velocities[best] / v[best]
        command = self.steer(observation, target, float(v[best]), self.config.heading_gain)
        return Decision(command, Plan("escape", float(v[best]), target, **base))


class _Search:
    """One cycle's x-y-t search, vectorised over nodes and obstacles."""

    def __init__(self, planner: ViaPathPlanner, position, heading_rad, subgoal, obstacles: Obstacles, radii):
        config = planner.config
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
        self.via_radii = self.check_radii + config.planning_margin_m
        self.horizon_s = config.horizon_s
        # Beyond an intermediate subgoal the robot carries on along the next segment.
        index = planner.subgoals.index
        self.continuation = None if planner.subgoals.is_final else (
            planner.path.segment_directions[index], planner.path.segment_lengths_m[index])
        # A robot already outside the corridor may not go further out, but may come back.
        self.corridor_allowance = max(0.0, float(self.path.corridor_excess(position)))

    # -- checks ----------------------------------------------------------------------------------

    def contact_times(self, starts, start_times, velocities, durations) -> np.ndarray:
        """(K, N) first contact of each leg with each obstacle, up to the horizon; inf = free."""
        if len(self.obstacles) == 0:
            return np.full((len(starts), 0), np.inf)
        checked = np.clip(self.horizon_s - start_times, 0.0, durations)
        return legs_first_contact(starts, start_times, velocities, checked, self.obstacles.positions,
                                  self.obstacles.velocities, self.check_radii, self.growth)

    def goal_legs(self, starts, start_times, speeds):
        """Straight legs from nodes to the subgoal: (directions, lengths, contact (K, N), inside (K,))."""
        offset = self.subgoal - starts
        lengths = np.hypot(offset[:, 0], offset[:, 1])
        directions = offset / np.maximum(lengths, 1e-12)[:, None]
        durations = lengths / speeds
        contact = self.contact_times(starts, start_times, directions * speeds[:, None], durations)
        if self.continuation is not None and contact.shape[1]:
            direction, length = self.continuation
            arrival = start_times + durations
            more = self.contact_times(np.repeat(self.subgoal[None], len(starts), 0), arrival,
                                      direction[None] * speeds[:, None], np.minimum(length / speeds, self.horizon_s))
            contact = np.minimum(contact, more + durations[:, None])
        inside = self.path.legs_inside(starts, np.repeat(self.subgoal[None], len(starts), 0),
                                       self.config.corridor_check_spacing_m, self.corridor_allowance + 1e-9)
        return directions, lengths, contact, inside

    def straight_is_free(self, speed: float) -> bool:
        _, _, contact, inside = self.goal_legs(self.position[None], np.zeros(1), np.array([speed]))
        return bool(inside[0] and np.isinf(contact).all())

    # -- search ----------------------------------------------------------------------------------

    def run(self, speeds: np.ndarray, previous_key):
        config = self.config
        nodes = _Nodes()
        n_speeds = len(speeds)
        frontier = nodes.extend(
            position=np.repeat(self.position[None], n_speeds, 0), time_s=np.zeros(n_speeds), speed=speeds,
            parent=np.full(n_speeds, -1), length_m=np.zeros(n_speeds), first_direction=np.zeros((n_speeds, 2)),
            key=np.stack([np.arange(n_speeds), np.full(n_speeds, -1), np.zeros(n_speeds, int), np.zeros(n_speeds, int)], 1),
        )
        data = nodes.stacked()
        complete, goal_length, goal_direction = [], [], []
        for depth in range(config.max_depth + 1):
            if len(frontier) == 0:
                break
            starts, times, node_speeds = data["position"][frontier], data["time_s"][frontier], data["speed"][frontier]
            directions, lengths, contact, inside = self.goal_legs(starts, times, node_speeds)
            free = inside & np.all(np.isinf(contact), axis=1)
            complete.append(frontier[free])
            goal_length.append(lengths[free])
            goal_direction.append(directions[free])
            if depth == 0:
                # A straight candidate's first leg is its goal leg.
                data["first_direction"][frontier] = directions
                nodes.first_direction[0] = directions
            if depth == config.max_depth or len(self.obstacles) == 0:
                break
            blocked = np.flatnonzero(~free & inside & np.isfinite(contact).any(axis=1))
            if depth == 0:
                pairs = self._root_pairs(contact[blocked])
                pair_nodes, pair_obstacles = frontier[blocked][pairs[0]], pairs[1]
            else:
                pair_nodes = frontier[blocked]
                pair_obstacles = np.argmin(contact[blocked], axis=1)
            children = self._expand(data, pair_nodes, pair_obstacles, is_root=(depth == 0))
            if children is None:
                break
            frontier = nodes.extend(**children)
            data = nodes.stacked()

        complete = np.concatenate(complete)
        if len(complete) == 0:
            return None
        goal_length = np.concatenate(goal_length)
        total_length = data["length_m"][complete] + goal_length
        speeds_c = data["speed"][complete]
        weights = config.weights
        theta = np.abs(wrap_angle(np.arctan2(data["first_direction"][complete, 1], data["first_direction"][complete, 0])
                                  - self.heading_rad))
        if config.theta_unit == "deg":
            theta = np.degrees(theta)
        cost = (weights.k1 * total_length + weights.k2 * total_length / speeds_c
                + weights.k3 * np.abs(speeds_c - self.planner.nominal_speed_mps) + weights.k4 * theta)
        keys = data["key"][complete]
        preferred = LEFT if config.preferred_side == "left" else RIGHT
        cost = cost + 1e-3 * ((keys[:, 2] != 0) & (keys[:, 2] != preferred))
        candidate_keys = [self._key(speeds_c[i], keys[i]) for i in range(len(complete))]
        if previous_key is not None:
            cost = cost - config.hysteresis * np.array([k == previous_key for k in candidate_keys])
        best = int(np.argmin(cost))
        polylines = [self._polyline(data, node) for node in complete]
        chosen_line = polylines[best]
        plan = Plan(
            status="avoid" if len(chosen_line) > 2 else "straight",
            speed_mps=float(speeds_c[best]),
            target=chosen_line[1].copy(),
            via_points=chosen_line[1:-1].copy(),
            waypoints=chosen_line,
            subgoal_index=self.planner.subgoals.index,
            candidate_count=len(complete),
            candidate_costs=cost,
            candidate_polylines=polylines,
            chosen=best,
        )
        return candidate_keys[best], plan

    @staticmethod
    def _key(speed, key_row) -> tuple:
        if key_row[1] < 0:
            return ("straight", round(float(speed), 3))
        return ("via", round(float(speed), 3), int(key_row[1]), int(key_row[2]), int(key_row[3]))

    def _root_pairs(self, contact: np.ndarray):
        """(row, obstacle) pairs to branch on at the root: each obstacle the leg hits, earliest first."""
        rows, cols = np.nonzero(np.isfinite(contact))
        limit = self.config.max_root_obstacles
        if limit and len(rows):
            order = np.lexsort((contact[rows, cols], rows))
            rows, cols = rows[order], cols[order]
            rank = np.arange(len(rows)) - np.searchsorted(rows, rows)
            keep = rank < limit
            rows, cols = rows[keep], cols[keep]
        return rows, cols

    def _expand(self, data, node_index, obstacle_index, is_root: bool):
        """Via-point children of each (node, obstacle) pair: both sides, both roots, legs checked."""
        if len(node_index) == 0:
            return None
        starts = data["position"][node_index]
        times = data["time_s"][node_index]
        speeds = data["speed"][node_index]
        obstacles = self.obstacles
        centre_now = obstacles.positions[obstacle_index] + obstacles.velocities[obstacle_index] * times[:, None]
        velocity = obstacles.velocities[obstacle_index]
        # The radius grows with prediction uncertainty; evaluate it near the expected passing time.
        reach_time = np.hypot(*(centre_now - starts).T) / speeds
        radius = self.via_radii[obstacle_index] + self.growth[obstacle_index] * (times + reach_time)

        sides = np.array([LEFT, RIGHT, LEFT, RIGHT])
        roots = np.array([0, 0, 1, 1])
        m = len(node_index)
        rep = lambda a: np.repeat(a, 4, axis=0)  # noqa: E731
        side_all, root_all = np.tile(sides, m), np.tile(roots, m)
        w, valid = tangent_vectors(rep(starts), rep(centre_now), rep(radius), side_all)
        t_early, t_late = via_times(w, rep(velocity), rep(speeds))
        t_via = np.where(root_all == 0, t_early, t_late)
        ok = valid & np.isfinite(t_via) & (t_via <= 3 * self.horizon_s)
        if not ok.any():
            return None
        idx = np.flatnonzero(ok)
        parent = rep(node_index)[idx]
        starts_k, times_k, speeds_k = rep(starts)[idx], rep(times)[idx], rep(speeds)[idx]
        t_k = t_via[idx]
        via = starts_k + w[idx] + rep(velocity)[idx] * t_k[:, None]
        leg_velocity = (via - starts_k) / t_k[:, None]
        contact = self.contact_times(starts_k, times_k, leg_velocity, t_k)
        inside = self.path.legs_inside(starts_k, via, self.config.corridor_check_spacing_m, self.corridor_allowance + 1e-9)
        good = inside & np.all(np.isinf(contact), axis=1)
        if not good.any():
            return None
        g = np.flatnonzero(good)
        direction = leg_velocity[g] / np.maximum(np.hypot(*leg_velocity[g].T), 1e-12)[:, None]
        parent_g = parent[g]
        if is_root:
            first_direction = direction
            key = np.stack([data["key"][parent_g, 0], obstacles.ids[rep(obstacle_index)[idx][g]],
                            side_all[idx][g], root_all[idx][g]], axis=1)
        else:
            first_direction = data["first_direction"][parent_g]
            key = data["key"][parent_g]
        return dict(
            position=via[g], time_s=times_k[g] + t_k[g], speed=speeds_k[g], parent=parent_g,
            length_m=data["length_m"][parent_g] + speeds_k[g] * t_k[g],
            first_direction=first_direction, key=key,
        )

    def _polyline(self, data, node: int) -> np.ndarray:
        points = [self.subgoal]
        while node >= 0:
            points.append(data["position"][node])
            node = int(data["parent"][node])
        return np.array(points[::-1])
