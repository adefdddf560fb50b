"""Step 4, the motion limits: the cheapest candidate the robot can actually follow.

Source: beyond the paper (its §5.2 names the robot's dynamics as future work); docs/design.md §2.

The x-y-t legs assume instant turns and speed changes. A candidate whose first leg needs a sharp turn
(more than ``rollout_heading_rad``) or a large speed change is rolled forward for ``rollout_s`` with
the controller that will drive it (arcs and lines within the limits, :func:`viapath.kinematics.track`)
and dropped if the roll-out touches an obstacle or leaves the corridor. Turning while moving can
swing out of the corridor: then the robot turns on the spot first, if standing is safe meanwhile
(the next cycles find it facing its leg). Even a small turn: at the corridor edge, or outside it
after an escape, a robot facing a little outwards would otherwise never get going again.
"""

from __future__ import annotations

import math

import numpy as np

from viapath.geometry import wrap_angle
from viapath.kinematics import UnicycleState
from viapath.observation import MotionLimits, Plan
from viapath.options import Settings
from viapath.planning.viapath.checks import LegChecks


def can_follow(plan: Plan, checks: LegChecks, limits: MotionLimits, config: Settings) -> bool:
    """Whether the robot, steering for the plan's target within its limits, keeps clear of every
    obstacle and inside the corridor. May mark the plan ``extras["turn_in_place"]``."""
    followed, turn_in_place = follows(plan.target, plan.speed_mps, checks, limits, config)
    if turn_in_place:
        plan.extras["turn_in_place"] = True
    return followed


def follows(
    target: np.ndarray, speed_mps: float, checks: LegChecks, limits: MotionLimits, config: Settings
) -> tuple[bool, bool]:
    """:func:`can_follow` of a plan that steers for ``target`` at ``speed_mps``, before the plan is made (in a
    cycle without a free candidate every plan would be made for nothing): (followed, turn in place first)."""
    offset = target - checks.position
    dx, dy = offset.tolist()
    heading_error = abs(float(wrap_angle(math.atan2(dy, dx) - checks.heading_rad)))  # libm's (geometry.angles_of)
    speed_change = abs(speed_mps - checks.speed_mps)
    if np.hypot(*offset) < 1e-6 or (
        heading_error <= config.rollout_heading_rad and speed_change <= limits.max_accel_mps2 * config.rollout_dt_s * 2
    ):
        return True, False
    # Candidates of a cycle often share the first leg's target and speed (slow/wait candidates, chains
    # through the same first via point): the roll-out and its verdict are then the same. Remembered for
    # the cycle's checks; a cycle without a free candidate rolls out up to max_rollouts of them.
    key = (float(target[0]), float(target[1]), float(speed_mps), id(limits), id(config))
    known = checks.__dict__.setdefault("_followed", {})
    if key not in known:
        known[key] = _roll_out(target, speed_mps, checks, limits, config, heading_error)
    return known[key]


def _roll_out(
    target: np.ndarray,
    speed_mps: float,
    checks: LegChecks,
    limits: MotionLimits,
    config: Settings,
    heading_error: float,
) -> tuple[bool, bool]:
    """(followed, turn in place first) of :func:`follows`' roll-out."""
    dt = config.rollout_dt_s
    steps = max(1, int(round(config.rollout_s / dt)))
    state = UnicycleState(
        float(checks.position[0]),
        float(checks.position[1]),
        float(checks.heading_rad),
        checks.speed_mps,
        checks.turn_rate_radps,
    )
    positions = checks.clear_track(state, target, speed_mps, limits, dt, steps, config.heading_gain)
    if positions is None:
        return False, False
    if checks.inside(positions).all():
        return True, False
    turn_s = heading_error / limits.max_turn_rate_radps + 1.0
    standing = np.repeat(checks.position[None], max(1, int(np.ceil(turn_s / dt))), axis=0)
    if heading_error > config.turn_in_place_min_rad and checks.clear(standing, dt):
        return True, True
    return False, False
