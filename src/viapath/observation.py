"""What every planner sees and what it returns (DESIGN §4, planner protocol).

Obstacles are held as arrays, one row per obstacle, so that planners can vectorise over them.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


class ObservationError(ValueError):
    """An observation that cannot be read as one: a field of the wrong shape or type. The message
    names the field (and the index where one value is at fault) and what was expected, e.g.
    ``obstacles.positions: expected an (N, 2) array of [x, y] rows, found shape (2, 5)``.
    Bad *values* (NaN, inf, out of range) in an observation of the right shape are not raised:
    :mod:`viapath.guard` keeps the obstacle conservatively or brakes, and reports it."""


def _numbers(field_name: str, value) -> np.ndarray:
    try:
        return np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ObservationError(f"obstacles.{field_name}: expected numbers, found {value!r}"[:300]) from None


def _points(field_name: str, value) -> np.ndarray:
    """(N, 2) rows; a flat [x, y] is one row and an empty array none. Nothing else is reshaped."""
    array = _numbers(field_name, value)
    if array.size == 0:
        return np.zeros((0, 2))
    if array.shape == (2,):
        return array.reshape(1, 2)
    if array.ndim != 2 or array.shape[1] != 2:
        hint = " (transposed? rows are obstacles)" if array.ndim == 2 and array.shape[0] == 2 else ""
        raise ObservationError(f"obstacles.{field_name}: expected an (N, 2) array of [x, y] rows, "
                               f"found shape {array.shape}{hint}")
    return array.copy()


def _per_obstacle(field_name: str, value, n: int) -> np.ndarray:
    """One number per obstacle, or one number for all of them."""
    array = _numbers(field_name, value)
    if array.ndim == 0:
        return np.full(n, float(array))
    if array.shape != (n,):
        raise ObservationError(f"obstacles.{field_name}: expected {n} numbers (one per position) or one number, "
                               f"found shape {array.shape}")
    return array.copy()


@dataclass(frozen=True)
class RobotState:
    """Pose and motion of a differential-drive robot in the world frame."""

    position: np.ndarray  # (2,) m
    heading_rad: float
    speed_mps: float
    turn_rate_radps: float = 0.0
    radius_m: float = 0.25

    @property
    def velocity(self) -> np.ndarray:
        return self.speed_mps * np.array([np.cos(self.heading_rad), np.sin(self.heading_rad)])


@dataclass(frozen=True)
class Obstacles:
    """Tracked obstacles under a constant-velocity forecast.

    ``velocity_sigma_mps`` is the standard deviation of each velocity estimate: planners that
    plan under uncertainty inflate the obstacle by ``k * sigma * t`` (the cylinder becomes a cone).
    """

    positions: np.ndarray  # (N, 2) m
    velocities: np.ndarray  # (N, 2) m/s
    radii_m: np.ndarray  # (N,) m
    position_sigma_m: np.ndarray | None = None  # (N,)
    velocity_sigma_mps: np.ndarray | None = None  # (N,)
    ids: np.ndarray | None = None  # (N,) int

    def __post_init__(self) -> None:
        # Shapes are checked here, once, with the field named (a transposed (2, N) array or lists of
        # different lengths must never be reshaped into phantom obstacles). Values (NaN, a negative
        # radius) are the guard's business: see viapath.guard.
        positions = _points("positions", self.positions)
        n = len(positions)
        velocities = _points("velocities", self.velocities)
        if len(velocities) != n:
            raise ObservationError(f"obstacles.velocities: expected {n} rows of [vx, vy] (one per position), "
                                   f"found {len(velocities)}")
        object.__setattr__(self, "positions", positions)
        object.__setattr__(self, "velocities", velocities)
        object.__setattr__(self, "radii_m", _per_obstacle("radii_m", self.radii_m, n))
        for name in ("position_sigma_m", "velocity_sigma_mps"):
            value = getattr(self, name)
            value = np.zeros(n) if value is None else _per_obstacle(name, value, n)
            object.__setattr__(self, name, value)
        if self.ids is None:
            ids = np.arange(n)
        else:
            ids = np.asarray(self.ids)
            if ids.ndim > 1 or ids.size != n:
                raise ObservationError(f"obstacles.ids: expected {n} ids (one per position), found shape {ids.shape}")
            try:
                ids = ids.astype(float).reshape(n)
            except (TypeError, ValueError):
                raise ObservationError(f"obstacles.ids: expected {n} integers, found {self.ids!r}") from None
            if not (np.isfinite(ids).all() and np.all(ids == np.round(ids))):
                raise ObservationError(f"obstacles.ids: expected {n} integers, found {ids.tolist()}")
            ids = ids.astype(int)
        object.__setattr__(self, "ids", ids)

    def __len__(self) -> int:
        return len(self.positions)

    @classmethod
    def empty(cls) -> "Obstacles":
        return cls(np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0))

    def finite(self) -> "Obstacles":
        """Drop rows with a NaN or infinite field: a bad estimate must never reach a command."""
        ok = (
            np.isfinite(self.positions).all(axis=1)
            & np.isfinite(self.velocities).all(axis=1)
            & np.isfinite(self.radii_m)
            & (self.radii_m >= 0)
            & np.isfinite(self.position_sigma_m)
            & np.isfinite(self.velocity_sigma_mps)
        )
        if ok.all():
            return self
        return self.subset(ok)

    def subset(self, mask_or_index) -> "Obstacles":
        return Obstacles(
            self.positions[mask_or_index],
            self.velocities[mask_or_index],
            self.radii_m[mask_or_index],
            self.position_sigma_m[mask_or_index],
            self.velocity_sigma_mps[mask_or_index],
            self.ids[mask_or_index],
        )


@dataclass(frozen=True)
class Observation:
    """One planning cycle's input: the same for every planner."""

    time_s: float
    robot: RobotState
    obstacles: Obstacles = field(default_factory=Obstacles.empty)


@dataclass(frozen=True)
class MotionLimits:
    """Differential-drive limits (defaults: a small indoor robot like the paper's)."""

    max_speed_mps: float = 0.6
    max_accel_mps2: float = 0.8
    max_turn_rate_radps: float = 2.0
    max_turn_accel_radps2: float = 6.0


@dataclass(frozen=True)
class Command:
    """Differential-drive command: forward speed and turn rate."""

    speed_mps: float
    turn_rate_radps: float

    @classmethod
    def stop(cls) -> "Command":
        return cls(0.0, 0.0)
