"""Baseline planners for the benchmark, behind the same protocol as the paper's planner.

All of them see the same :class:`~viapath.observation.Observation` (tracked obstacles with velocities
and uncertainty), head for the same subgoal (:class:`~viapath.path.SubgoalTracker`, paper §2) and
return a (v, ω) command within the same :class:`~viapath.observation.MotionLimits`, every cycle of the
same 10 Hz loop.

* ``follow``: heads for the subgoal at the nominal speed; no avoidance at all (the lower bound).
* ``stop``: as ``follow``, but stops while its straight leg to the subgoal is predicted to touch an
  obstacle within ``horizon_s`` (constant-velocity forecast).
* ``dwa``: dynamic window approach. Source: D. Fox, W. Burgard, S. Thrun, "The dynamic window
  approach to collision avoidance", IEEE Robotics & Automation Magazine 4(1), 1997: circular
  trajectories of constant (v, ω) from the window of velocities reachable in one control period;
  admissible ones are ranked by G = σ(α·heading + β·dist + γ·velocity).
* ``vo``: velocity obstacles, sampled. Source: P. Fiorini, Z. Shiller, "Motion planning in dynamic
  environments using velocity obstacles", IJRR 17(7), 1998: a velocity u is in the (time-truncated)
  VO of obstacle i when the relative motion u − v_i reaches the disc of combined radius within the
  horizon; among reachable velocities outside every VO the one closest to the preferred velocity
  ("TG", to goal) is taken.

What the sources leave open and we chose (and why):
* Obstacles are forecast at constant velocity; the combined radius is robot + obstacle +
  ``safety_margin_m`` + ``uncertainty_sigmas``·position σ, growing by ``uncertainty_sigmas``·velocity σ
  per second (the same cone as the paper's planner), so every planner gets the same safety inflation.
* The corridor (DESIGN §4) is a hard constraint in ``dwa`` and ``vo``: a candidate whose motion over
  ``corridor_horizon_s`` leaves it is dropped (a robot already outside may not go further out). Only
  the first seconds are checked: a constant-(v, ω) arc checked to the full horizon leaves any corridor.
* DWA: Fox et al. reward high speed; a path follower should keep its nominal speed, so the velocity
  term rewards closeness to the nominal speed. We add a path term (lateral deviation after the
  lookahead, relative to the half-width) so the robot returns to the path. Admissible = no predicted
  contact along the arc within ``horizon_s`` (with moving obstacles "can stop before the obstacle"
  does not guarantee safety). With no admissible arc: brake (v = 0), turning by the arc with the
  latest contact (the braking fallback).
* VO: candidates are ``n_speeds`` speeds × headings within ±``heading_span_rad`` of the direction to
  the subgoal, plus standing still. Exact ties (head-on) go to ``preferred_side``. With no velocity
  outside every VO, the one minimising ``penalty_weight / time_to_contact + |u − u_pref|`` is taken
  (the usual RVO-style penalty). A velocity is turned into (v, ω) by the shared ``steer``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from viapath.geometry import closest_approach, legs_first_contact, wrap_angle
from viapath.observation import Command, Observation, Obstacles
from viapath.planning.base import Decision, Plan, Planner


def _inflation(obstacles: Obstacles, robot_radius_m: float, safety_margin_m: float, sigmas: float):
    """Combined radius per obstacle and its growth rate (m/s) from the velocity uncertainty."""
    radii = obstacles.radii_m + robot_radius_m + safety_margin_m + sigmas * obstacles.position_sigma_m
    return radii, sigmas * obstacles.velocity_sigma_mps


class _SubgoalFollower(Planner):
    """Shared by the baselines: subgoal tracking (paper §2) and the obstacle list every cycle."""

    def _prepare(self, observation: Observation):
        position = np.asarray(observation.robot.position, dtype=float)
        obstacles = observation.obstacles.finite()
        self.subgoals.update(position, self.robot_radius_m, obstacles.positions, obstacles.radii_m)
        return position, obstacles, self.subgoals.subgoal

    def _goal_decision(self, position) -> Decision | None:
        if self.subgoals.goal_reached(position):
            subgoal = self.subgoals.subgoal
            return Decision(Command.stop(), Plan("goal", 0.0, subgoal.copy(), subgoal_index=self.subgoals.index))
        return None

    def _straight(self, observation, position, subgoal, status="straight") -> Decision:
        speed = self.nominal_speed_mps
        plan = Plan(status, speed, subgoal.copy(), waypoints=np.array([position, subgoal]),
                    subgoal_index=self.subgoals.index)
        return Decision(self.steer(observation, subgoal, speed), plan)


class FollowPlanner(_SubgoalFollower, name="follow"):
    """Follows the designated path at the nominal speed and ignores obstacles (the lower bound)."""

    def plan(self, observation: Observation) -> Decision:
        position, _, subgoal = self._prepare(observation)
        return self._goal_decision(position) or self._straight(observation, position, subgoal)


class StopPlanner(_SubgoalFollower, name="stop"):
    """Follows the path; stops while the straight leg ahead is predicted to touch an obstacle."""

    def __init__(self, path, *, horizon_s: float = 4.0, safety_margin_m: float = 0.05,
                 uncertainty_sigmas: float = 2.0, **kwargs):
        super().__init__(path, **kwargs)
        self.horizon_s = float(horizon_s)
        self.safety_margin_m = float(safety_margin_m)
        self.uncertainty_sigmas = float(uncertainty_sigmas)

    def plan(self, observation: Observation) -> Decision:
        position, obstacles, subgoal = self._prepare(observation)
        done = self._goal_decision(position)
        if done is not None:
            return done
        if len(obstacles):
            offset = subgoal - position
            distance = float(np.hypot(*offset))
            speed = self.nominal_speed_mps
            velocity = offset / max(distance, 1e-9) * speed
            duration = min(self.horizon_s, distance / speed)
            radii, growth = _inflation(obstacles, self.robot_radius_m, self.safety_margin_m, self.uncertainty_sigmas)
            contact = legs_first_contact(position[None], np.zeros(1), velocity[None], np.array([duration]),
                                         obstacles.positions, obstacles.velocities, radii, growth)
            if np.isfinite(contact).any():
                return Decision(Command.stop(), Plan("stop", 0.0, position.copy(), subgoal_index=self.subgoals.index))
        return self._straight(observation, position, subgoal)


@dataclass
class DWAConfig:
    horizon_s: float = 3.0  # an arc touching an obstacle this far ahead is inadmissible
    sample_dt_s: float = 0.1
    window_s: float = 0.1  # the control period: velocities reachable within it form the window
    n_speeds: int = 7
    n_turn_rates: int = 15
    corridor_horizon_s: float = 1.5
    heading_lookahead_s: float = 1.0
    heading_weight: float = 1.0  # α
    clearance_weight: float = 0.3  # β
    velocity_weight: float = 0.3  # γ
    path_weight: float = 0.5  # our addition: stay near the designated path
    safety_margin_m: float = 0.05
    uncertainty_sigmas: float = 2.0


class DWAPlanner(_SubgoalFollower, name="dwa"):
    """Dynamic window approach (Fox, Burgard, Thrun 1997) with predicted obstacle motion and the corridor."""

    def __init__(self, path, *, config: DWAConfig | None = None, **kwargs):
        options = {k: kwargs.pop(k) for k in list(kwargs) if k in DWAConfig.__dataclass_fields__}
        super().__init__(path, **kwargs)
        self.config = config or DWAConfig(**options)

    def plan(self, observation: Observation) -> Decision:
        config, limits = self.config, self.limits
        position, obstacles, subgoal = self._prepare(observation)
        done = self._goal_decision(position)
        if done is not None:
            return done
        robot = observation.robot
        # The dynamic window: velocities reachable within one control period.
        dv, dw = limits.max_accel_mps2 * config.window_s, limits.max_turn_accel_radps2 * config.window_s
        speeds = np.linspace(max(0.0, robot.speed_mps - dv), min(limits.max_speed_mps, robot.speed_mps + dv), config.n_speeds)
        turns = np.linspace(max(-limits.max_turn_rate_radps, robot.turn_rate_radps - dw),
                            min(limits.max_turn_rate_radps, robot.turn_rate_radps + dw), config.n_turn_rates)
        v, w = (a.ravel() for a in np.meshgrid(speeds, turns))
        # Arcs are followed to twice the horizon: contact within the horizon makes an arc inadmissible;
        # the time to the first contact up to twice the horizon is the "dist" term (Fox et al.: distance
        # to the first obstacle on the curvature, a large constant when none).
        times = np.arange(int(round(2 * config.horizon_s / config.sample_dt_s)) + 1) * config.sample_dt_s
        poses = _arcs(position, robot.heading_rad, v, w, times)  # (K, S, 3)
        xy = poses[..., :2]
        first_contact = np.full(len(v), np.inf)
        if len(obstacles):
            radii, growth = _inflation(obstacles, self.robot_radius_m, config.safety_margin_m, config.uncertainty_sigmas)
            reach = np.hypot(*(obstacles.positions - position).T) - radii
            reach_limit = (limits.max_speed_mps + np.hypot(*obstacles.velocities.T) + growth) * times[-1]
            near = reach <= reach_limit
            if near.any():
                # Exact closest approach for straight motion of both between samples.
                centres = obstacles.positions[near][None, :, :] + times[:, None, None] * obstacles.velocities[near][None]
                rel = xy[:, :, None, :] - centres[None]  # (K, S, N, 2)
                distance, _ = closest_approach(rel[:, :-1], rel[:, 1:] - rel[:, :-1], 1.0)
                gaps = distance - (radii[near] + growth[near] * times[1:, None])[None]
                touching = (gaps <= 0).any(axis=2)
                first_contact = np.where(touching, times[:-1][None], np.inf).min(axis=1)
        admissible = first_contact > config.horizon_s
        clearance_term = np.minimum(first_contact, times[-1]) / times[-1]

        # The corridor as a constraint over its own, shorter horizon.
        corridor_samples = times <= config.corridor_horizon_s + 1e-9
        tolerance = max(0.0, float(self.path.corridor_excess(position))) + 1e-6
        inside = (self.path.corridor_excess(xy[:, corridor_samples]) <= tolerance).all(axis=1)
        admissible &= inside

        if not admissible.any():
            # Braking fallback: stop, turning along the arc whose contact (or exit) comes latest.
            best = int(np.argmax(np.where(inside, 1e3, 0.0) + np.minimum(first_contact, 1e3)))
            plan = Plan("brake", 0.0, xy[best, -1].copy(), waypoints=xy[best].copy(), subgoal_index=self.subgoals.index,
                        candidate_count=0)
            return Decision(Command(0.0, float(w[best])), plan)

        look = min(int(round(config.heading_lookahead_s / config.sample_dt_s)), len(times) - 1)
        ahead = poses[:, look]
        to_goal = subgoal - ahead[:, :2]
        heading_error = np.abs(wrap_angle(np.arctan2(to_goal[:, 1], to_goal[:, 0]) - ahead[:, 2]))
        # At the subgoal itself the bearing is undefined: count it as aligned.
        heading_error = np.where(np.hypot(*to_goal.T) < 0.05, 0.0, heading_error)
        heading_term = 1.0 - heading_error / np.pi
        velocity_term = 1.0 - np.abs(v - self.nominal_speed_mps) / limits.max_speed_mps
        half_width = self.path.half_widths_m[min(self.subgoals.index - 1, len(self.path.half_widths_m) - 1)]
        path_term = 1.0 - np.clip(np.abs(self.path.lateral_deviation(ahead[:, :2])) / half_width, 0.0, 1.0)
        score = (config.heading_weight * heading_term + config.clearance_weight * clearance_term
                 + config.velocity_weight * velocity_term + config.path_weight * path_term)
        score = np.where(admissible, score, -np.inf)
        best = int(np.argmax(score))
        plan = Plan("dwa", float(v[best]), xy[best, look].copy(), waypoints=xy[best].copy(),
                    subgoal_index=self.subgoals.index, candidate_count=int(admissible.sum()),
                    candidate_costs=-score[admissible], extras={"turn_rate_radps": float(w[best])})
        return Decision(Command(float(v[best]), float(w[best])), plan)


def _arcs(position, heading_rad, speeds, turn_rates, times):
    """Poses (K, S, 3) along constant-(v, ω) arcs from the robot pose."""
    t = times[None, :]
    v, w = speeds[:, None], turn_rates[:, None]
    heading = heading_rad + w * t
    straight = np.abs(w) < 1e-6
    safe_w = np.where(straight, 1.0, w)
    x = np.where(straight, v * t * np.cos(heading_rad), v / safe_w * (np.sin(heading) - np.sin(heading_rad)))
    y = np.where(straight, v * t * np.sin(heading_rad), -v / safe_w * (np.cos(heading) - np.cos(heading_rad)))
    return np.stack([position[0] + x, position[1] + y, heading], axis=-1)


@dataclass
class VOConfig:
    horizon_s: float = 5.0  # truncation of the velocity obstacles
    n_speeds: int = 7
    n_headings: int = 37
    heading_span_rad: float = np.pi / 2
    corridor_horizon_s: float = 2.0
    preferred_side: str = "left"
    penalty_weight: float = 0.5
    safety_margin_m: float = 0.05
    uncertainty_sigmas: float = 2.0


class VOPlanner(_SubgoalFollower, name="vo"):
    """Sampling-based velocity obstacles (Fiorini & Shiller 1998) with the corridor."""

    def __init__(self, path, *, config: VOConfig | None = None, **kwargs):
        options = {k: kwargs.pop(k) for k in list(kwargs) if k in VOConfig.__dataclass_fields__}
        super().__init__(path, **kwargs)
        self.config = config or VOConfig(**options)
        if self.config.preferred_side not in ("left", "right"):
            raise ValueError("preferred_side must be 'left' or 'right'")

    def plan(self, observation: Observation) -> Decision:
        config = self.config
        position, obstacles, subgoal = self._prepare(observation)
        done = self._goal_decision(position)
        if done is not None:
            return done
        offset = subgoal - position
        bearing = float(np.arctan2(offset[1], offset[0]))
        preferred = self.nominal_speed_mps * np.array([np.cos(bearing), np.sin(bearing)])
        top = min(self.limits.max_speed_mps, max(self.nominal_speed_mps * 2.0, self.nominal_speed_mps + 0.1))
        speeds = np.unique(np.concatenate([np.linspace(top / config.n_speeds, top, config.n_speeds),
                                           [min(self.nominal_speed_mps, top)]]))
        deflection = np.linspace(-config.heading_span_rad, config.heading_span_rad, config.n_headings)
        s, d = (a.ravel() for a in np.meshgrid(speeds, deflection))
        s, d = np.append(s, 0.0), np.append(d, 0.0)  # standing still is a candidate too
        candidates = s[:, None] * np.stack([np.cos(bearing + d), np.sin(bearing + d)], axis=1)
        k = len(candidates)

        if len(obstacles):
            radii, growth = _inflation(obstacles, self.robot_radius_m, config.safety_margin_m, config.uncertainty_sigmas)
            contact = legs_first_contact(np.repeat(position[None], k, 0), np.zeros(k), candidates,
                                         np.full(k, config.horizon_s), obstacles.positions, obstacles.velocities,
                                         radii, growth).min(axis=1)
        else:
            contact = np.full(k, np.inf)
        tolerance = max(0.0, float(self.path.corridor_excess(position))) + 1e-6
        ends = position + candidates * config.corridor_horizon_s
        inside = self.path.legs_inside(np.repeat(position[None], k, 0), ends, tolerance_m=tolerance)
        free = np.isinf(contact) & inside

        distance = np.hypot(*(candidates - preferred).T)
        # Exact ties (head-on) go to the preferred side: a tiny cost on the other side's deflections.
        other_side = (d < 0) if config.preferred_side == "left" else (d > 0)
        cost = distance + 1e-6 * other_side
        if free.any():
            best = int(np.argmin(np.where(free, cost, np.inf)))
            status = "vo"
        else:
            penalty = config.penalty_weight / np.maximum(contact, 1e-3) + cost + np.where(inside, 0.0, 1e3)
            best = int(np.argmin(penalty))
            status = "vo-penalty"
        velocity = candidates[best]
        speed = float(s[best])
        target = position + velocity / max(speed, 1e-9) if speed > 0 else position.copy()
        plan = Plan(status, speed, target, waypoints=np.array([position, position + velocity * config.horizon_s]),
                    subgoal_index=self.subgoals.index, candidate_count=int(free.sum()))
        command = self.steer(observation, target, speed) if speed > 0 else Command.stop()
        return Decision(command, plan)


# navground's behaviours (ORCA, HL, HRVO, SocialForce) register only when the package is installed.
try:  # pragma: no cover - depends on the optional extra
    import importlib.util as _util

    if _util.find_spec("navground") is not None:
        import viapath.planning.navground_peers  # noqa: F401
except ImportError:
    pass
