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
* The corridor (docs/design.md §4) is a hard constraint in ``dwa`` and ``vo``: a candidate whose motion over
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

from typing import Any

import numpy as np

from viapath.geometry import closest_approach, legs_first_contact, wrap_angle
from viapath.observation import Command, Decision, Plan, RobotState
from viapath.options import Option, OptionSet
from viapath.path import DesignatedPath
from viapath.planning.base import COMMON_OPTIONS, Planner, Situation


class _SubgoalFollower(Planner):
    """Shared by the baselines: the straight leg to the subgoal (paper §2) and the options as attributes."""

    def __init__(self, path: DesignatedPath, **kwargs: Any) -> None:
        super().__init__(path, **kwargs)
        self.config = self.settings

    def _straight(self, situation: Situation, status: str = "straight") -> Decision:
        speed, position, subgoal = self.nominal_speed_mps, situation.position, situation.subgoal
        plan = Plan(
            status,
            speed,
            subgoal.copy(),
            waypoints=np.array([position, subgoal]),
            subgoal_index=situation.subgoal_index,
        )
        return Decision(self.steer(situation.observation, subgoal, speed), plan)


class FollowPlanner(_SubgoalFollower, name="follow"):
    """Follows the designated path at the nominal speed and ignores obstacles (the lower bound)."""

    def decide(self, situation: Situation) -> Decision:
        return self._straight(situation)


class StopPlanner(_SubgoalFollower, name="stop"):
    """Follows the path; stops while the straight leg ahead is predicted to touch an obstacle."""

    options = COMMON_OPTIONS + OptionSet(
        [
            Option(
                "horizon_s",
                4.0,
                "stop while the straight leg touches an obstacle this far ahead",
                "s",
                minimum=0.0,
                exclusive_minimum=True,
                maximum=60.0,
            ),
        ],
        owner="stop",
    )

    def decide(self, situation: Situation) -> Decision:
        obstacles, position, subgoal = situation.obstacles, situation.position, situation.subgoal
        if len(obstacles):
            offset = subgoal - position
            distance = float(np.hypot(*offset))
            speed = self.nominal_speed_mps
            velocity = offset / max(distance, 1e-9) * speed
            duration = min(self.config.horizon_s, distance / speed)
            inflation = situation.inflation
            contact = legs_first_contact(
                position[None],
                np.zeros(1),
                velocity[None],
                np.array([duration]),
                obstacles.positions,
                obstacles.velocities,
                inflation.check_radii,
                inflation.growth,
                inflation.growth_until_s,
            )
            if np.isfinite(contact).any():
                return Decision(
                    Command.stop(), Plan("stop", 0.0, position.copy(), subgoal_index=situation.subgoal_index)
                )
        return self._straight(situation)


class DWAPlanner(_SubgoalFollower, name="dwa"):
    """Dynamic window approach (Fox, Burgard, Thrun 1997) with predicted obstacle motion and the corridor."""

    options = COMMON_OPTIONS + OptionSet(
        [
            Option(
                "horizon_s",
                3.0,
                "an arc touching an obstacle this far ahead is inadmissible",
                "s",
                minimum=0.25,
                maximum=10.0,
            ),  # at least a quarter of the longest sample_dt_s: arcs of 2 samples
            Option("sample_dt_s", 0.1, "time step of the sampled arcs", "s", minimum=0.05, maximum=1.0),
            Option(
                "window_s",
                0.1,
                "the control period: velocities reachable within it form the window",
                "s",
                minimum=0.0,
                exclusive_minimum=True,
                maximum=10.0,
            ),
            Option("n_speeds", 7, "speeds sampled in the window", minimum=1, maximum=21),
            Option("n_turn_rates", 15, "turn rates sampled in the window", minimum=1, maximum=41),
            Option(
                "corridor_horizon_s", 1.5, "an arc must stay in the corridor this long", "s", minimum=0.0, maximum=30.0
            ),
            Option(
                "heading_lookahead_s",
                1.0,
                "where along the arc heading and path terms are evaluated",
                "s",
                minimum=0.0,
                maximum=30.0,
            ),
            Option("heading_weight", 1.0, "α, weight of the heading to the subgoal", minimum=0.0, maximum=1000.0),
            Option("clearance_weight", 0.3, "β, weight of the time to the first contact", minimum=0.0, maximum=1000.0),
            Option("velocity_weight", 0.3, "γ, weight of closeness to the nominal speed", minimum=0.0, maximum=1000.0),
            Option(
                "path_weight",
                0.5,
                "weight of staying near the designated path (our addition)",
                minimum=0.0,
                maximum=1000.0,
            ),
        ],
        owner="dwa",
        steps=[("horizon_s", "sample_dt_s")],
    )

    def decide(self, situation: Situation) -> Decision:
        config = self.config
        position, robot = situation.position, situation.robot
        v, w = self._window(robot)
        # Arcs are followed to twice the horizon: contact within the horizon makes an arc inadmissible;
        # the time to the first contact up to twice the horizon is the "dist" term (Fox et al.: distance
        # to the first obstacle on the curvature, a large constant when none).
        times = np.arange(int(round(2 * config.horizon_s / config.sample_dt_s)) + 1) * config.sample_dt_s
        poses = _arcs(position, robot.heading_rad, v, w, times)  # (K, S, 3)
        xy = poses[..., :2]
        first_contact = _first_contact(situation, xy, times, self.limits.max_speed_mps)
        admissible = first_contact > config.horizon_s
        clearance_term = np.minimum(first_contact, times[-1]) / times[-1]

        # The corridor as a constraint over its own, shorter horizon.
        corridor_samples = times <= config.corridor_horizon_s + 1e-9
        tolerance = situation.corridor_excess_m + 1e-6
        inside = (self.path.corridor_excess(xy[:, corridor_samples]) <= tolerance).all(axis=1)
        admissible &= inside

        if not admissible.any():
            # Braking fallback: stop, turning along the arc whose contact (or exit) comes latest.
            best = int(np.argmax(np.where(inside, 1e3, 0.0) + np.minimum(first_contact, 1e3)))
            plan = Plan(
                "brake",
                0.0,
                xy[best, -1].copy(),
                waypoints=xy[best].copy(),
                subgoal_index=situation.subgoal_index,
                candidate_count=0,
            )
            return Decision(Command(0.0, float(w[best])), plan)

        look = min(int(round(config.heading_lookahead_s / config.sample_dt_s)), len(times) - 1)
        score = self._score(situation, poses[:, look], v, clearance_term)
        score = np.where(admissible, score, -np.inf)
        best = int(np.argmax(score))
        plan = Plan(
            "dwa",
            float(v[best]),
            xy[best, look].copy(),
            waypoints=xy[best].copy(),
            subgoal_index=situation.subgoal_index,
            candidate_count=int(admissible.sum()),
            candidate_costs=-score[admissible],
            extras={"turn_rate_radps": float(w[best])},
        )
        return Decision(Command(float(v[best]), float(w[best])), plan)

    def _window(self, robot: RobotState) -> tuple[np.ndarray, np.ndarray]:
        """The dynamic window: (speeds, turn rates) of the sampled pairs reachable within one control period."""
        config, limits = self.config, self.limits
        dv, dw = limits.max_accel_mps2 * config.window_s, limits.max_turn_accel_radps2 * config.window_s
        speeds = np.linspace(
            max(0.0, robot.speed_mps - dv), min(limits.max_speed_mps, robot.speed_mps + dv), config.n_speeds
        )
        turns = np.linspace(
            max(-limits.max_turn_rate_radps, robot.turn_rate_radps - dw),
            min(limits.max_turn_rate_radps, robot.turn_rate_radps + dw),
            config.n_turn_rates,
        )
        v, w = (a.ravel() for a in np.meshgrid(speeds, turns))
        return v, w

    def _score(self, situation: Situation, ahead: np.ndarray, v: np.ndarray, clearance_term: np.ndarray) -> np.ndarray:
        """Fox et al.'s weighted sum (heading, clearance, velocity) plus the path term, per arc, from
        the poses ``ahead`` at the lookahead time."""
        config, limits = self.config, self.limits
        to_goal = situation.subgoal - ahead[:, :2]
        heading_error = np.abs(wrap_angle(np.arctan2(to_goal[:, 1], to_goal[:, 0]) - ahead[:, 2]))
        # At the subgoal itself the bearing is undefined: count it as aligned.
        heading_error = np.where(np.hypot(*to_goal.T) < 0.05, 0.0, heading_error)
        heading_term = 1.0 - heading_error / np.pi
        velocity_term = 1.0 - np.abs(v - self.nominal_speed_mps) / limits.max_speed_mps
        half_width = self.path.half_widths_m[min(situation.subgoal_index - 1, len(self.path.half_widths_m) - 1)]
        path_term = 1.0 - np.clip(np.abs(self.path.lateral_deviation(ahead[:, :2])) / half_width, 0.0, 1.0)
        return (
            config.heading_weight * heading_term
            + config.clearance_weight * clearance_term
            + config.velocity_weight * velocity_term
            + config.path_weight * path_term
        )


def _first_contact(situation: Situation, xy: np.ndarray, times: np.ndarray, max_speed_mps: float) -> np.ndarray:
    """Per arc (sampled at ``times``), the sample time before its first contact with an obstacle's
    inflated disc (exact closest approach between samples, both moving straight); inf when none."""
    obstacles, position = situation.obstacles, situation.position
    first_contact = np.full(len(xy), np.inf)
    if len(obstacles):
        radii, growth, until = (
            situation.inflation.check_radii,
            situation.inflation.growth,
            situation.inflation.growth_until_s,
        )
        reach = np.hypot(*(obstacles.positions - position).T) - radii
        reach_limit = (max_speed_mps + np.hypot(*obstacles.velocities.T) + growth) * times[-1]
        near = reach <= reach_limit
        if near.any():
            # Exact closest approach for straight motion of both between samples.
            centres = obstacles.positions[near][None, :, :] + times[:, None, None] * obstacles.velocities[near][None]
            rel = xy[:, :, None, :] - centres[None]  # (K, S, N, 2)
            distance, _ = closest_approach(rel[:, :-1], rel[:, 1:] - rel[:, :-1], 1.0)
            gaps = distance - (radii[near] + growth[near] * np.minimum(times[1:, None], until[near]))[None]
            touching = (gaps <= 0).any(axis=2)
            first_contact = np.where(touching, times[:-1][None], np.inf).min(axis=1)
    return first_contact


def _arcs(
    position: np.ndarray, heading_rad: float, speeds: np.ndarray, turn_rates: np.ndarray, times: np.ndarray
) -> np.ndarray:
    """Poses (K, S, 3) along constant-(v, ω) arcs from the robot pose."""
    t = times[None, :]
    v, w = speeds[:, None], turn_rates[:, None]
    heading = heading_rad + w * t
    straight = np.abs(w) < 1e-6
    safe_w = np.where(straight, 1.0, w)
    x = np.where(straight, v * t * np.cos(heading_rad), v / safe_w * (np.sin(heading) - np.sin(heading_rad)))
    y = np.where(straight, v * t * np.sin(heading_rad), -v / safe_w * (np.cos(heading) - np.cos(heading_rad)))
    return np.stack([position[0] + x, position[1] + y, heading], axis=-1)


class VOPlanner(_SubgoalFollower, name="vo"):
    """Sampling-based velocity obstacles (Fiorini & Shiller 1998) with the corridor."""

    options = COMMON_OPTIONS + OptionSet(
        [
            Option(
                "horizon_s",
                5.0,
                "truncation of the velocity obstacles",
                "s",
                minimum=0.0,
                exclusive_minimum=True,
                maximum=60.0,
            ),
            Option("n_speeds", 7, "speeds sampled up to the top speed", minimum=1, maximum=51),
            Option("n_headings", 37, "headings sampled around the direction to the subgoal", minimum=1, maximum=181),
            Option(
                "heading_span_rad",
                float(np.pi / 2),
                "headings within ± this of the direction to the subgoal",
                "rad",
                minimum=0.0,
                maximum=float(np.pi),
            ),
            Option(
                "corridor_horizon_s",
                2.0,
                "a velocity must keep the robot in the corridor this long",
                "s",
                minimum=0.0,
                maximum=30.0,
            ),
            Option("preferred_side", "left", "exact ties (head-on) go round this side", choices=("left", "right")),
            Option(
                "penalty_weight",
                0.5,
                "with no free velocity: weight of 1/time-to-contact",
                "s",
                minimum=0.0,
                maximum=1000.0,
            ),
        ],
        owner="vo",
    )

    def decide(self, situation: Situation) -> Decision:
        config = self.config
        obstacles, position, subgoal = situation.obstacles, situation.position, situation.subgoal
        offset = subgoal - position
        bearing = float(np.arctan2(offset[1], offset[0]))
        preferred = self.nominal_speed_mps * np.array([np.cos(bearing), np.sin(bearing)])
        top = min(self.limits.max_speed_mps, max(self.nominal_speed_mps * 2.0, self.nominal_speed_mps + 0.1))
        speeds = np.unique(
            np.concatenate(
                [np.linspace(top / config.n_speeds, top, config.n_speeds), [min(self.nominal_speed_mps, top)]]
            )
        )
        deflection = np.linspace(-config.heading_span_rad, config.heading_span_rad, config.n_headings)
        s, d = (a.ravel() for a in np.meshgrid(speeds, deflection))
        s, d = np.append(s, 0.0), np.append(d, 0.0)  # standing still is a candidate too
        candidates = s[:, None] * np.stack([np.cos(bearing + d), np.sin(bearing + d)], axis=1)
        k = len(candidates)

        if len(obstacles):
            inflation = situation.inflation
            contact = legs_first_contact(
                np.repeat(position[None], k, 0),
                np.zeros(k),
                candidates,
                np.full(k, config.horizon_s),
                obstacles.positions,
                obstacles.velocities,
                inflation.check_radii,
                inflation.growth,
                inflation.growth_until_s,
            ).min(axis=1)
        else:
            contact = np.full(k, np.inf)
        tolerance = situation.corridor_excess_m + 1e-6
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
        plan = Plan(
            status,
            speed,
            target,
            waypoints=np.array([position, position + velocity * config.horizon_s]),
            subgoal_index=situation.subgoal_index,
            candidate_count=int(free.sum()),
        )
        command = self.steer(situation.observation, target, speed) if speed > 0 else Command.stop()
        return Decision(command, plan)
