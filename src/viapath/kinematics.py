"""Differential-drive (unicycle) motion under speed, acceleration and turn-rate limits.

Core, not simulator: the planner rolls its controller forward with the same model that the
simulator drives the robot with, so a plan the robot cannot follow is caught before it is sent.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from viapath.observation import Command, MotionLimits


@dataclass
class UnicycleState:
    x: float
    y: float
    heading_rad: float
    speed_mps: float = 0.0
    turn_rate_radps: float = 0.0

    @property
    def position(self) -> np.ndarray:
        return np.array([self.x, self.y])


def limit_command(command: Command, state: UnicycleState, limits: MotionLimits, dt_s: float) -> tuple[float, float]:
    """The (v, ω) the drive actually achieves this step; a non-finite command is taken as stop."""
    v_cmd, w_cmd = float(command.speed_mps), float(command.turn_rate_radps)
    if not (math.isfinite(v_cmd) and math.isfinite(w_cmd)):
        v_cmd, w_cmd = 0.0, 0.0
    v_cmd = _clip(v_cmd, 0.0, limits.max_speed_mps)
    w_cmd = _clip(w_cmd, -limits.max_turn_rate_radps, limits.max_turn_rate_radps)
    dv = limits.max_accel_mps2 * dt_s
    dw = limits.max_turn_accel_radps2 * dt_s
    speed = state.speed_mps + _clip(v_cmd - state.speed_mps, -dv, dv)
    turn = state.turn_rate_radps + _clip(w_cmd - state.turn_rate_radps, -dw, dw)
    return speed, turn


def step(state: UnicycleState, command: Command, limits: MotionLimits, dt_s: float) -> UnicycleState:
    """Advance one step along the exact arc of the limited (v, ω)."""
    speed, turn = limit_command(command, state, limits, dt_s)
    x, y, heading = _arc(state.x, state.y, state.heading_rad, speed, turn, dt_s)
    return UnicycleState(x, y, heading, speed, turn)


# _arc and _clip are compiled from this source by viapath.guard_checks and the planner's roll-out
# (jit.compiled(kinematics._arc)); naming the decorator here puts this file in the compiled cache's digest
# (viapath.jit.source_digest), so that a change to them is compiled afresh in their callers.
def _arc(x: float, y: float, heading: float, speed: float, turn: float, dt_s: float) -> tuple[float, float, float]:
    """Where constant (v, ω) for ``dt_s`` takes the robot: along the exact arc (a line for ω = 0)."""
    # The chord of the arc: length v·dt·sin(h)/h with h = ω·dt/2, along the mean heading. Exact, and
    # stable for tiny ω (v/ω·(sin a − sin b) loses ~1e-8 m at ω ~ 1e-9 rad/s).
    new_heading = heading + turn * dt_s
    half = 0.5 * turn * dt_s
    chord = speed * dt_s * (1.0 - half * half / 6.0 if abs(half) < 1e-6 else math.sin(half) / half)
    x += chord * math.cos(heading + half)
    y += chord * math.sin(heading + half)
    return x, y, math.atan2(math.sin(new_heading), math.cos(new_heading))


def _clip(value: float, low: float, high: float) -> float:
    return low if value < low else high if value > high else value


def steer_towards(
    x: float,
    y: float,
    heading_rad: float,
    target_x: float,
    target_y: float,
    speed_mps: float,
    limits: MotionLimits,
    heading_gain: float = 2.5,
) -> tuple[float, float]:
    """The controller: turn towards the target and drive at ``speed_mps``, slowing for large
    heading errors (full speed up to 45° off, none from 90°: a sharp turn is made nearly on the spot)."""
    dx, dy = target_x - x, target_y - y
    if dx * dx + dy * dy < 1e-18 or speed_mps <= 0:
        return 0.0, 0.0
    error = math.atan2(dy, dx) - heading_rad
    error = math.atan2(math.sin(error), math.cos(error))
    turn = _clip(heading_gain * error, -limits.max_turn_rate_radps, limits.max_turn_rate_radps)
    scale = _clip((math.pi / 2 - abs(error)) / (math.pi / 4), 0.0, 1.0)
    return min(speed_mps, limits.max_speed_mps) * scale, turn
