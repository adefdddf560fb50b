"""What every planner sees and what it returns (DESIGN §4, planner protocol).

Obstacles are held as arrays, one row per obstacle, so that planners can vectorise over them.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


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
        positions = np.asarray(self.positions, dtype=float).reshape(-1, 2)
        n = len(positions)
        object.__setattr__(self, "positions", positions)
        object.__setattr__(self, "velocities", np.asarray(self.velocities, dtype=float).reshape(n, 2))
        object.__setattr__(self, "radii_m", np.broadcast_to(np.asarray(self.radii_m, dtype=float), (n,)).copy())
        for name in ("position_sigma_m", "velocity_sigma_mps"):
            value = getattr(self, name)
            value = np.zeros(n) if value is None else np.broadcast_to(np.asarray(value, dtype=float), (n,)).copy()
            object.__setattr__(self, name, value)
        ids = np.arange(n) if self.ids is None else np.asarray(self.ids, dtype=int).reshape(n)
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
