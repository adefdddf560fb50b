"""Whether the robot can follow a candidate (the paper's §3, the choice's last condition): the
controller stepped within the motion limits as :func:`viapath.kinematics.step` moves the robot (:func:`track`),
and whether such a roll-out keeps clear of every person and inside the corridor (:func:`_clear`,
:func:`can_follow`). Compiled steps, the one implementation of each.
"""

from __future__ import annotations

import math

import numpy as np

from viapath import kinematics
from viapath.jit import compiled
from viapath.planning.viapath.legs import clip, excess_at_most

# The drive's exact arc, compiled from the simulator's own (inlined: called per step of every roll-out).
_arc = compiled(inline=True)(kinematics._arc)


@compiled(inline=True)
def steer(
    x: float,
    y: float,
    heading: float,
    target_x: float,
    target_y: float,
    speed_mps: float,
    max_speed_mps: float,
    max_turn_rate_radps: float,
    heading_gain: float,
) -> tuple[float, float]:
    """The command (speed, turn rate) steering for the target at ``speed_mps``: the compiled form of
    :func:`viapath.kinematics.steer_towards` (the planner's command law)."""
    dx = target_x - x
    dy = target_y - y
    if dx * dx + dy * dy < 1e-18 or speed_mps <= 0:
        return 0.0, 0.0
    error = math.atan2(dy, dx) - heading
    error = math.atan2(math.sin(error), math.cos(error))
    w_cmd = clip(heading_gain * error, -max_turn_rate_radps, max_turn_rate_radps)
    scale = clip((math.pi / 2 - abs(error)) / (math.pi / 4), 0.0, 1.0)
    return min(speed_mps, max_speed_mps) * scale, w_cmd


@compiled(inline=True)
def drive_step(
    x: float,
    y: float,
    heading: float,
    speed: float,
    turn: float,
    v_cmd: float,
    w_cmd: float,
    dv: float,
    dw: float,
    dt_s: float,
) -> tuple[float, float, float, float, float]:
    """One step of the drive: speed and turn rate ramped towards the command by at most ``dv`` and ``dw``, then
    the exact arc, as :func:`viapath.kinematics.step` moves the robot. Returns (x, y, heading, speed, turn)."""
    speed += clip(v_cmd - speed, -dv, dv)
    turn += clip(w_cmd - turn, -dw, dw)
    x, y, heading = _arc(x, y, heading, speed, turn, dt_s)
    return x, y, heading, speed, turn


@compiled
def track(
    x,
    y,
    heading,
    speed,
    turn,
    target_x,
    target_y,
    speed_mps,
    max_speed_mps,
    max_turn_rate_radps,
    max_accel_mps2,
    max_turn_accel_radps2,
    dt_s,
    steps,
    heading_gain,
):
    """(steps, 2) positions of the robot steering for the target: the compiled form of
    :func:`viapath.kinematics.track` (:func:`steer`, then :func:`drive_step`)."""
    dv = max_accel_mps2 * dt_s
    dw = max_turn_accel_radps2 * dt_s
    positions = np.empty((steps, 2))
    for k in range(steps):
        v_cmd, w_cmd = steer(
            x, y, heading, target_x, target_y, speed_mps, max_speed_mps, max_turn_rate_radps, heading_gain
        )
        x, y, heading, speed, turn = drive_step(x, y, heading, speed, turn, v_cmd, w_cmd, dv, dw, dt_s)
        positions[k, 0] = x
        positions[k, 1] = y
    return positions


@compiled
def wrap(angle):
    """:func:`viapath.geometry.wrap_angle` of a scalar (np.mod's sign convention is Python's %)."""
    turned = math.pi - angle
    if 0.0 <= turned < 2.0 * math.pi:  # % leaves it as it is (fmod exact; ±0.0 gives pi either way): skip it
        return math.pi - turned
    return math.pi - (turned % (2.0 * math.pi))


@compiled
def _clear(
    positions, count, dt, robot_x, robot_y, obstacle_positions, obstacle_velocities, radii, growth, growth_until_s
):
    """Whether the first ``count`` positions (one per ``dt`` from now) keep clear of every obstacle: each at least its
    reach then from it, or (a close pass) no closer than the robot is now."""
    for j in range(obstacle_positions.shape[0]):
        now = math.hypot(robot_x - obstacle_positions[j, 0], robot_y - obstacle_positions[j, 1]) - 1e-3
        for s in range(count):
            t = dt * (s + 1)
            cx = obstacle_positions[j, 0] + obstacle_velocities[j, 0] * t
            cy = obstacle_positions[j, 1] + obstacle_velocities[j, 1] * t
            until = growth_until_s[j]
            capped = until if until != until else (t if t < until else until)  # np.minimum keeps a NaN
            reach = radii[j] + growth[j] * capped
            limit = reach if (reach != reach or reach < now) else now  # np.minimum, NaN first
            if now != now:
                limit = now
            dx = positions[s, 0] - cx
            dy = positions[s, 1] - cy
            # hypot >= limit by the squared distance outside a ±1e-9 band (as _within), else by hypot itself:
            # NaN offsets or limits, and limits whose square could underflow or overflow, go to hypot.
            if 1e-140 < limit < 1e140:
                squared = dx * dx + dy * dy
                above = limit * (1.0 + 1e-9)
                if squared > above * above:
                    continue
                below = limit * (1.0 - 1e-9)
                if squared < below * below:
                    return False
            if not math.hypot(dx, dy) >= limit:
                return False
    return True


@compiled(inline=True)
def _close_enough(robot, target_x, target_y, heading_error, speed, settings):
    """Whether the robot follows without a roll-out: the target is where it stands, or it heads for it within
    the roll-out's heading and is within two steps' acceleration of the speed."""
    ox = target_x - robot[0]
    oy = target_y - robot[1]
    speed_change = abs(speed - robot[3])
    dt = settings.rollout_dt_s
    return math.hypot(ox, oy) < 1e-6 or (
        heading_error <= settings.rollout_heading_rad and speed_change <= settings.max_accel_mps2 * dt * 2
    )


@compiled(inline=True)
def _roll_out(robot, target_x, target_y, speed, settings, steps):
    """The (steps, 2) positions of the robot steering for the target at ``speed`` (:func:`track`)."""
    return track(
        robot[0],
        robot[1],
        robot[2],
        robot[3],
        robot[4],
        target_x,
        target_y,
        speed,
        settings.max_speed_mps,
        settings.max_turn_rate_radps,
        settings.max_accel_mps2,
        settings.max_turn_accel_radps2,
        settings.rollout_dt_s,
        steps,
        settings.heading_gain,
    )


@compiled(inline=True)
def keeps_inside(positions, count, corridor, tolerance):
    """Whether the first ``count`` positions keep within ``tolerance`` of the corridor."""
    segment_starts, segment_directions, segment_lengths, half_widths = corridor
    for s in range(count):
        if not excess_at_most(
            positions[s, 0],
            positions[s, 1],
            segment_starts,
            segment_directions,
            segment_lengths,
            half_widths,
            tolerance,
        ):
            return False
    return True


@compiled(inline=True)
def _clear_turning_on_the_spot(robot, heading_error, settings, obstacles):
    """Whether standing at the robot's position keeps clear (:func:`_clear`) while it turns by ``heading_error`` at
    its top turn rate, and a second more."""
    dt = settings.rollout_dt_s
    turn_s = heading_error / settings.max_turn_rate_radps + 1.0
    count = max(1, int(math.ceil(turn_s / dt)))
    standing = np.empty((count, 2))
    for s in range(count):
        standing[s, 0] = robot[0]
        standing[s, 1] = robot[1]
    return _clear(standing, count, dt, robot[0], robot[1], *obstacles)


@compiled
def can_follow(robot, target_x, target_y, angle, speed, settings, steps, obstacles, corridor):
    """follow.can_follow: 0 cannot, 1 can, 2 can after turning on the spot first. ``angle``: atan2 of the
    offset from the robot to the target; ``obstacles`` and ``corridor``: :func:`grow`'s records. The roll-out
    steering for the target must keep clear of everyone (:func:`_clear`); then it can if the roll-out keeps inside
    the corridor, or, turning a lot, if standing while it turns on the spot keeps clear."""
    heading_error = abs(wrap(angle - robot[2]))
    if _close_enough(robot, target_x, target_y, heading_error, speed, settings):
        return 1
    positions = _roll_out(robot, target_x, target_y, speed, settings, steps)
    if not _clear(positions, steps, settings.rollout_dt_s, robot[0], robot[1], *obstacles):
        return 0
    if keeps_inside(positions, steps, corridor, settings.corridor_tolerance_m):
        return 1
    if heading_error > settings.turn_in_place_min_rad and _clear_turning_on_the_spot(
        robot, heading_error, settings, obstacles
    ):
        return 2
    return 0
