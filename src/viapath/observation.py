"""What every planner sees and what it returns (docs/design.md §4, planner protocol).

Obstacles are held as arrays, one row per obstacle, so that planners can vectorise over them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from viapath.limits import LIMITS_OPTIONS
from viapath.static import StaticLayer


class ObservationError(ValueError):
    """An observation that cannot be read as one: a field of the wrong shape or type. The message
    names the field (and the index where one value is at fault) and what was expected, e.g.
    ``obstacles.positions: expected an (N, 2) array of [x, y] rows, found shape (2, 5)``.
    Bad *values* (NaN, inf, out of range) in an observation of the right shape are not raised:
    :mod:`viapath.guard` keeps the obstacle conservatively or brakes, and reports it."""


def _numbers(field_name: str, value: Any) -> np.ndarray:
    try:
        return np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ObservationError(f"obstacles.{field_name}: expected numbers, found {value!r}"[:300]) from None


def _points(field_name: str, value: Any) -> np.ndarray:
    """(N, 2) rows; a flat [x, y] is one row and an empty array none. Nothing else is reshaped."""
    array = _numbers(field_name, value)
    if array.size == 0:
        return np.zeros((0, 2))
    if array.shape == (2,):
        return array.reshape(1, 2)
    if array.ndim != 2 or array.shape[1] != 2:
        hint = " (transposed? rows are obstacles)" if array.ndim == 2 and array.shape[0] == 2 else ""
        raise ObservationError(
            f"obstacles.{field_name}: expected an (N, 2) array of [x, y] rows, found shape {array.shape}{hint}"
        )
    return array.copy()


def _per_obstacle(field_name: str, value: Any, n: int) -> np.ndarray:
    """One number per obstacle, or one number for all of them."""
    array = _numbers(field_name, value)
    if array.ndim == 0:
        return np.full(n, float(array))
    if array.shape != (n,):
        raise ObservationError(
            f"obstacles.{field_name}: expected {n} numbers (one per position) or one number, found shape {array.shape}"
        )
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


def _is_number(value: object) -> bool:
    """A real number (not text, None or a complex): what an obstacle id may be made of."""
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)


def _whole_ids(ids: np.ndarray) -> np.ndarray:
    """Whole float ids (|id| <= 2**63) as int64. 2**63 itself (an int64 near its maximum, rounded
    through float) becomes the largest int64 a float holds: a plain cast would wrap it to the minimum,
    with numpy's "invalid value" warning."""
    return np.clip(ids, -(2.0**63), np.nextafter(2.0**63, 0.0)).astype(np.int64)


@dataclass(frozen=True)
class Obstacles:
    """Tracked obstacles under a constant-velocity forecast.

    ``velocity_sigma_mps`` is the standard deviation of each velocity estimate: planners that
    plan under uncertainty inflate the obstacle by ``k * sigma * t`` (the cylinder becomes a cone).
    """

    positions: np.ndarray  # (N, 2) m
    velocities: np.ndarray  # (N, 2) m/s
    radii_m: np.ndarray  # (N,) m
    # Given as None, these three are filled in by __post_init__ (zeros, zeros, 0..N-1): typed as what they hold.
    position_sigma_m: np.ndarray = None  # type: ignore[assignment]  # (N,)
    velocity_sigma_mps: np.ndarray = None  # type: ignore[assignment]  # (N,)
    ids: np.ndarray = None  # type: ignore[assignment]  # (N,) int
    # (N,) bool: rows that are static geometry (viapath.static), not people; None = none is.
    static_mask: np.ndarray | None = None

    def __post_init__(self) -> None:
        self._set_static_mask()
        # Shapes are checked here, once, with the field named (a transposed (2, N) array or lists of
        # different lengths must never be reshaped into phantom obstacles). Values (NaN, a negative
        # radius) are the guard's business: see viapath.guard.
        if self._set_well_formed():
            return
        positions = _points("positions", self.positions)
        n = len(positions)
        velocities = _points("velocities", self.velocities)
        if len(velocities) != n:
            raise ObservationError(
                f"obstacles.velocities: expected {n} rows of [vx, vy] (one per position), found {len(velocities)}"
            )
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
                if np.iscomplexobj(ids) or (ids.dtype.kind in "USO" and not all(_is_number(i) for i in ids.ravel())):
                    raise TypeError("not numbers")
                ids = ids.astype(float).reshape(n)
            except (TypeError, ValueError, OverflowError):
                raise ObservationError(f"obstacles.ids: expected {n} integers, found {self.ids!r}") from None
            if not (np.isfinite(ids).all() and np.all(ids == np.round(ids)) and np.all(np.abs(ids) <= 2.0**63)):
                raise ObservationError(f"obstacles.ids: expected {n} 64-bit integers, found {ids.tolist()}")
            ids = _whole_ids(ids)
        object.__setattr__(self, "ids", ids)

    def _set_static_mask(self) -> None:
        n = np.shape(self.positions)[0] if np.ndim(self.positions) == 2 else -1
        mask = self.static_mask
        if mask is None or n < 0:
            return
        mask = np.asarray(mask, dtype=bool).reshape(-1)
        if mask.shape != (n,):
            raise ObservationError(f"obstacles.static_mask: expected {n} flags (one per position), found {mask.size}")
        object.__setattr__(self, "static_mask", mask if mask.any() else None)

    @property
    def is_static(self) -> np.ndarray:
        """(N,) bool: which rows are static geometry."""
        return np.zeros(len(self.positions), dtype=bool) if self.static_mask is None else self.static_mask

    @property
    def static_count(self) -> int:
        return 0 if self.static_mask is None else int(self.static_mask.sum())

    def people(self) -> Obstacles:
        """The rows that are not static geometry."""
        return self if self.static_mask is None else self.subset(~self.static_mask)

    def statics(self) -> Obstacles:
        """The rows that are static geometry."""
        return self.subset(self.is_static)

    @classmethod
    def of_fresh_arrays(
        cls,
        positions: np.ndarray,
        velocities: np.ndarray,
        radii_m: np.ndarray,
        position_sigma_m: np.ndarray,
        velocity_sigma_mps: np.ndarray,
        ids: np.ndarray,
    ) -> Obstacles:
        """Obstacles from arrays made for them and used by no one else (a perception's estimates): when
        they are well formed (float64 (N, 2), (N, 2), (N,), (N,), (N,) and (N,) integer ids) they are
        kept as they are instead of copied; anything else goes through the checks of the constructor."""
        n = len(positions) if type(positions) is np.ndarray and positions.ndim == 2 else -1
        if (
            n >= 0
            and positions.dtype == np.float64
            and positions.shape == (n, 2)
            and isinstance(ids, np.ndarray)
            and ids.shape == (n,)
            and ids.dtype == np.int64
            and all(
                type(a) is np.ndarray and a.dtype == np.float64 and a.shape == shape
                for a, shape in (
                    (velocities, (n, 2)),
                    (radii_m, (n,)),
                    (position_sigma_m, (n,)),
                    (velocity_sigma_mps, (n,)),
                )
            )
        ):
            obstacles = object.__new__(cls)
            ids = _whole_ids(ids.astype(float))  # as the constructor: through float (ids past 2**53 round)
            for name, value in (
                ("positions", positions),
                ("velocities", velocities),
                ("radii_m", radii_m),
                ("position_sigma_m", position_sigma_m),
                ("velocity_sigma_mps", velocity_sigma_mps),
                ("ids", ids),
            ):
                object.__setattr__(obstacles, name, value)
            return obstacles
        return cls(positions, velocities, radii_m, position_sigma_m, velocity_sigma_mps, ids)

    def _set_well_formed(self) -> bool:
        """The common case (perception hands float64 arrays of the right shapes, integer ids): the same
        copies as the general path below, without its conversions and checks; False for anything else."""
        positions, velocities, radii = self.positions, self.velocities, self.radii_m
        if not (
            type(positions) is np.ndarray
            and positions.dtype == np.float64
            and positions.ndim == 2
            and positions.shape[1] == 2
        ):
            return False
        n = positions.shape[0]
        arrays = [velocities, radii, self.position_sigma_m, self.velocity_sigma_mps]
        shapes = [(n, 2), (n,), (n,), (n,)]
        for k, (array, shape) in enumerate(zip(arrays, shapes)):
            if array is None and k >= 2:
                arrays[k] = np.zeros(n)
            elif type(array) is np.ndarray and array.dtype == np.float64 and array.shape == shape:
                arrays[k] = array.copy()
            else:
                return False
        ids = self.ids
        if ids is None:
            ids = np.arange(n)
        elif type(ids) is np.ndarray and ids.shape == (n,) and ids.dtype.kind in "iu":
            as_float = ids.astype(float)  # as the general path: through float (always whole, finite)
            if ids.dtype.kind == "u" and n and as_float.max() > 2.0**63:
                return False  # the general path refuses it, naming the ids
            ids = _whole_ids(as_float)
        else:
            return False
        object.__setattr__(self, "positions", positions.copy())
        for name, array in zip(("velocities", "radii_m", "position_sigma_m", "velocity_sigma_mps"), arrays):
            object.__setattr__(self, name, array)
        object.__setattr__(self, "ids", ids)
        return True

    def __len__(self) -> int:
        return len(self.positions)

    @classmethod
    def empty(cls) -> Obstacles:
        return cls(np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0))

    def finite(self) -> Obstacles:
        """Drop rows with a NaN or infinite field: a bad estimate must never reach a command."""
        if len(self.positions) == 0:
            return self
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

    def subset(self, mask_or_index: Any) -> Obstacles:
        return Obstacles(
            self.positions[mask_or_index],
            self.velocities[mask_or_index],
            self.radii_m[mask_or_index],
            self.position_sigma_m[mask_or_index],
            self.velocity_sigma_mps[mask_or_index],
            self.ids[mask_or_index],
            None if self.static_mask is None else self.static_mask[mask_or_index],
        )


@dataclass(frozen=True)
class Observation:
    """One planning cycle's input: the same for every planner."""

    time_s: float
    robot: RobotState
    obstacles: Obstacles = field(default_factory=Obstacles.empty)
    # Static geometry in the world frame (walls, boxes, unexplained scan returns): see viapath.static.
    # The guarded entry of every planner (viapath.guard) turns it into static rows of ``obstacles``.
    static: StaticLayer = field(default_factory=StaticLayer.empty)

    def __post_init__(self) -> None:
        if type(self.static) is not StaticLayer and not isinstance(self.static, StaticLayer):
            raise ObservationError(
                "static: expected a viapath.static.StaticLayer (e.g. StaticLayer(segments) with segments an "
                f"(M, 2, 2) array), found {type(self.static).__name__}"
            )


@dataclass(frozen=True)
class MotionLimits:
    """Differential-drive limits; defaults, units and bounds: :data:`viapath.limits.LIMITS_OPTIONS`."""

    max_speed_mps: float = LIMITS_OPTIONS["max_speed_mps"].default
    max_accel_mps2: float = LIMITS_OPTIONS["max_accel_mps2"].default
    max_turn_rate_radps: float = LIMITS_OPTIONS["max_turn_rate_radps"].default
    max_turn_accel_radps2: float = LIMITS_OPTIONS["max_turn_accel_radps2"].default


@dataclass(frozen=True)
class Command:
    """Differential-drive command: forward speed and turn rate."""

    speed_mps: float
    turn_rate_radps: float

    @classmethod
    def stop(cls) -> Command:
        return cls(0.0, 0.0)


@dataclass
class Plan:
    """What a planner intends, for display and analysis. Planners fill what applies to them."""

    status: str  # e.g. "straight", "avoid", "stop", "escape", "goal"
    speed_mps: float
    target: np.ndarray  # the point the robot steers for now
    via_points: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    waypoints: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))  # chosen polyline from the robot
    subgoal_index: int = 1
    candidate_count: int = 0
    candidate_costs: np.ndarray = field(default_factory=lambda: np.zeros(0))
    candidate_polylines: list[np.ndarray] = field(default_factory=list)
    chosen: int | None = None
    extras: dict[str, Any] = field(default_factory=dict)


@dataclass
class Decision:
    command: Command
    plan: Plan
