"""Differential-drive (unicycle) motion under speed, acceleration and turn-rate limits.

Core, not simulator: the planner rolls its controller forward with the same model that the
simulator drives the robot with, so a plan the robot cannot follow is caught before it is sent.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterator, Sequence
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


def rollout(
    state: UnicycleState,
    commands: np.ndarray,
    limits: MotionLimits,
    dt_s: float,
    steps: int,
    turns: tuple[np.ndarray, np.ndarray] | None = None,
) -> np.ndarray:
    """Positions (K, steps, 2) after each step of holding each of K commands (v, ω) from ``state``:
    the same limited arcs as :func:`step`, vectorised over the commands and the steps (a held
    command makes speed and turn rate ramp to it at the acceleration limits, so both are known in
    closed form; the positions are then running sums of the arcs). ``turns``, when given: the distinct
    turn commands (T,) and each command's index among them (K,)."""
    commands = np.asarray(commands, dtype=float).reshape(-1, 2)
    # np.clip's max-then-min as the two ufuncs (the same values; np.clip's dispatch costs more than the
    # arithmetic on these small arrays), and each sine and cosine taken once: the heading before a step
    # is the heading after the previous one. The escape rolls out its fan of commands every cycle
    # without a free candidate (tests/test_kinematics.py: bit for bit the earlier, plainer form).
    v_cmd = np.minimum(np.maximum(commands[:, 0], 0.0), limits.max_speed_mps)
    ramp = np.arange(1, steps + 1)
    speed0, turn0 = float(state.speed_mps), float(state.turn_rate_radps)
    dv, dw = limits.max_accel_mps2 * dt_s * ramp, limits.max_turn_accel_radps2 * dt_s * ramp
    speed = speed0 + np.minimum(np.maximum((v_cmd - speed0)[:, None], -dv), dv)  # (K, steps), during each step
    # Turn rates and headings depend on the turn command alone: with ``turns`` (the escape's fan: 9 turn rates,
    # each with every speed) they, and their sines and cosines, are made once per turn command and copied to
    # its commands, the same values row for row.
    w_cmd = np.minimum(
        np.maximum(commands[:, 1] if turns is None else turns[0], -limits.max_turn_rate_radps),
        limits.max_turn_rate_radps,
    )
    turn = turn0 + np.minimum(np.maximum((w_cmd - turn0)[:, None], -dw), dw)
    headings = np.empty((len(w_cmd), steps + 1))  # before the first step, then after each
    headings[:, 0] = float(state.heading_rad)
    headings[:, 1:] = float(state.heading_rad) + (turn * dt_s).cumsum(axis=1)
    sines, cosines = np.sin(headings), np.cos(headings)
    if turns is not None:
        rows = turns[1]
        turn, sines, cosines = turn[rows], sines[rows], cosines[rows]
    sin_before, sin_after = sines[:, :-1], sines[:, 1:]
    cos_before, cos_after = cosines[:, :-1], cosines[:, 1:]
    straight = np.abs(turn) < 1e-9
    radius = speed / np.where(straight, 1.0, turn)
    dx = np.where(straight, speed * dt_s * cos_before, radius * (sin_after - sin_before))
    dy = np.where(straight, speed * dt_s * sin_before, -radius * (cos_after - cos_before))
    positions = np.empty((len(commands), steps, 2))
    positions[..., 0] = float(state.x) + dx.cumsum(axis=1)
    positions[..., 1] = float(state.y) + dy.cumsum(axis=1)
    return positions


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


def track(
    state: UnicycleState,
    target: Sequence[float] | np.ndarray,
    speed_mps: float,
    limits: MotionLimits,
    dt_s: float,
    steps: int,
    heading_gain: float = 2.5,
) -> np.ndarray:
    """Positions (steps, 2) of the robot steering for ``target`` with :func:`steer_towards`, each
    step as :func:`step` moves it (scalar arithmetic: this runs inside the planning cycle)."""
    positions = list(itertools.islice(tracking(state, target, speed_mps, limits, dt_s, heading_gain), steps))
    return np.array(positions).reshape(steps, 2)


def tracking(
    state: UnicycleState,
    target: Sequence[float] | np.ndarray,
    speed_mps: float,
    limits: MotionLimits,
    dt_s: float,
    heading_gain: float = 2.5,
) -> Iterator[tuple[float, float]]:
    """:func:`track`'s positions (x, y) one step at a time, without end: a caller that checks them as they
    come can stop a roll-out that has failed (the roll-outs of failing candidates, :mod:`.follow`)."""
    # steer_towards and _arc inlined, operation for operation (the positions are bit for bit theirs:
    # tests/test_kinematics.py): a candidate that fails is rolled out, up to max_rollouts of them in a
    # cycle without a free candidate, and the calls cost more than the arithmetic (docs/speed.md).
    x, y, heading = float(state.x), float(state.y), float(state.heading_rad)
    speed, turn = float(state.speed_mps), float(state.turn_rate_radps)
    target_x, target_y = float(target[0]), float(target[1])
    dv, dw = limits.max_accel_mps2 * dt_s, limits.max_turn_accel_radps2 * dt_s
    max_turn, top_speed = limits.max_turn_rate_radps, min(speed_mps, limits.max_speed_mps)
    quarter_turn, eighth_turn = math.pi / 2, math.pi / 4
    atan2, sin, cos = math.atan2, math.sin, math.cos
    standing = speed_mps <= 0
    while True:
        dx, dy = target_x - x, target_y - y
        if dx * dx + dy * dy < 1e-18 or standing:
            v_cmd = w_cmd = 0.0
        else:
            error = atan2(dy, dx) - heading
            error = atan2(sin(error), cos(error))
            w_cmd = heading_gain * error
            w_cmd = -max_turn if w_cmd < -max_turn else max_turn if w_cmd > max_turn else w_cmd
            scale = (quarter_turn - abs(error)) / eighth_turn
            v_cmd = top_speed * (0.0 if scale < 0.0 else 1.0 if scale > 1.0 else scale)
        change = v_cmd - speed
        speed += -dv if change < -dv else dv if change > dv else change
        change = w_cmd - turn
        turn += -dw if change < -dw else dw if change > dw else change
        new_heading = heading + turn * dt_s
        half = 0.5 * turn * dt_s
        chord = speed * dt_s * (1.0 - half * half / 6.0 if abs(half) < 1e-6 else sin(half) / half)
        mean_heading = heading + half
        x += chord * cos(mean_heading)
        y += chord * sin(mean_heading)
        heading = atan2(sin(new_heading), cos(new_heading))
        yield x, y
