"""Differential-drive (unicycle) robot that obeys speed, acceleration and turn-rate limits."""

from __future__ import annotations

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
    v_cmd, w_cmd = command.speed_mps, command.turn_rate_radps
    if not (np.isfinite(v_cmd) and np.isfinite(w_cmd)):
        v_cmd, w_cmd = 0.0, 0.0
    v_cmd = float(np.clip(v_cmd, 0.0, limits.max_speed_mps))
    w_cmd = float(np.clip(w_cmd, -limits.max_turn_rate_radps, limits.max_turn_rate_radps))
    dv = limits.max_accel_mps2 * dt_s
    dw = limits.max_turn_accel_radps2 * dt_s
    speed = state.speed_mps + float(np.clip(v_cmd - state.speed_mps, -dv, dv))
    turn = state.turn_rate_radps + float(np.clip(w_cmd - state.turn_rate_radps, -dw, dw))
    return speed, turn


def step(state: UnicycleState, command: Command, limits: MotionLimits, dt_s: float) -> UnicycleState:
    """Advance one step along the exact arc of the limited (v, ω)."""
    speed, turn = limit_command(command, state, limits, dt_s)
    heading = state.heading_rad
    if abs(turn) < 1e-9:
        x = state.x + speed * dt_s * np.cos(heading)
        y = state.y + speed * dt_s * np.sin(heading)
    else:
        new_heading = heading + turn * dt_s
        x = state.x + speed / turn * (np.sin(new_heading) - np.sin(heading))
        y = state.y - speed / turn * (np.cos(new_heading) - np.cos(heading))
    heading = float(np.angle(np.exp(1j * (heading + turn * dt_s))))
    return UnicycleState(float(x), float(y), heading, speed, turn)
