"""2-D laser scanner model: Hokuyo URG-04LX defaults, mounting pose, noise and invalid readings.

Source: Yamada, Sa, Ohya §1.2 and §4.1 (two URG-04LX, 240° each, one facing forward and one
backward, each 0.145 m from the robot centre) and the URG-04LX datasheet as quoted in docs/design.md §3:
0.352° steps (360°/1024; 683 beams over 240°), 100 ms per scan, 0.02–4.0 m guaranteed range with
readings reported up to 5.6 m, accuracy ±10 mm below 1 m and ±1 % of the range beyond.

What the sources leave open and we chose:
* Noise is Gaussian on the range with σ equal to the datasheet accuracy (10 mm below 1 m, 1 % of
  the range beyond): the datasheet's "±" read as one standard deviation, a conservative reading.
* A beam that hits nothing, or whose noisy range falls outside [range_min_m, range_max_m], is
  *invalid*. Real drivers report invalid readings as +inf (urg_node, ROS 2), NaN, or 0 / a value
  below range_min (hokuyo_node, ROS 1): ``invalid_encoding`` picks which one the simulated scanner
  emits, and :func:`sanitize_ranges` accepts all of them on input and turns them into NaN.
* Beams are simultaneous: the 100 ms sweep's motion distortion is not modelled (at 0.5 m/s the
  robot moves 5 cm during a sweep; the tracker's measurement noise absorbs it).
* Beam angles are symmetric about the scanner's axis: ``(i - (n - 1)/2) * angle_increment_rad``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

URG04LX_ANGLE_INCREMENT_RAD = 2.0 * np.pi / 1024.0  # 0.3515625°
URG04LX_BEAM_COUNT = 683  # 240° / 0.3515625° + 1
URG04LX_MOUNT_OFFSET_M = 0.145  # paper §4.1: each scanner 0.145 m from the robot centre

INVALID_ENCODINGS = ("inf", "nan", "zero")


@dataclass(frozen=True)
class ScannerModel:
    """One planar laser scanner and its mounting pose in the robot frame (x forward, y left)."""

    name: str = "front"
    mount_x_m: float = URG04LX_MOUNT_OFFSET_M
    mount_y_m: float = 0.0
    mount_yaw_rad: float = 0.0
    beam_count: int = URG04LX_BEAM_COUNT
    angle_increment_rad: float = URG04LX_ANGLE_INCREMENT_RAD
    range_min_m: float = 0.02
    range_max_m: float = 5.6
    scan_period_s: float = 0.1
    noise_sigma_near_m: float = 0.010  # σ below noise_switch_range_m
    noise_fraction_far: float = 0.01  # σ = fraction * range beyond it
    noise_switch_range_m: float = 1.0
    invalid_encoding: str = "inf"

    def __post_init__(self) -> None:
        for field_name in (
            "mount_x_m",
            "mount_y_m",
            "mount_yaw_rad",
            "angle_increment_rad",
            "range_min_m",
            "range_max_m",
            "scan_period_s",
            "noise_sigma_near_m",
            "noise_fraction_far",
            "noise_switch_range_m",
        ):
            if not np.isfinite(getattr(self, field_name)):
                raise ValueError(f"scanner {self.name!r}: {field_name} must be finite")
        if self.beam_count < 2:
            raise ValueError(f"scanner {self.name!r}: beam_count must be >= 2, got {self.beam_count}")
        if not self.angle_increment_rad > 0:
            raise ValueError(f"scanner {self.name!r}: angle_increment_rad must be > 0")
        if (self.beam_count - 1) * self.angle_increment_rad > 2.0 * np.pi + 1e-9:
            raise ValueError(f"scanner {self.name!r}: field of view exceeds 360°")
        if not 0 <= self.range_min_m < self.range_max_m:
            raise ValueError(f"scanner {self.name!r}: need 0 <= range_min_m < range_max_m")
        if self.noise_sigma_near_m < 0 or self.noise_fraction_far < 0:
            raise ValueError(f"scanner {self.name!r}: noise must be >= 0")
        if self.invalid_encoding not in INVALID_ENCODINGS:
            raise ValueError(f"scanner {self.name!r}: invalid_encoding must be one of {INVALID_ENCODINGS}")

    @classmethod
    def urg04lx(cls, name: str = "front", facing: str = "forward", **overrides) -> ScannerModel:
        """A URG-04LX at ±0.145 m on the robot axis facing ``forward`` or ``backward`` (paper §4.1)."""
        if facing == "forward":
            pose = dict(mount_x_m=URG04LX_MOUNT_OFFSET_M, mount_y_m=0.0, mount_yaw_rad=0.0)
        elif facing == "backward":
            pose = dict(mount_x_m=-URG04LX_MOUNT_OFFSET_M, mount_y_m=0.0, mount_yaw_rad=np.pi)
        else:
            raise ValueError(f"facing must be 'forward' or 'backward', got {facing!r}")
        return cls(name=name, **{**pose, **overrides})

    @property
    def field_of_view_rad(self) -> float:
        return (self.beam_count - 1) * self.angle_increment_rad

    @property
    def angle_min_rad(self) -> float:
        return -0.5 * self.field_of_view_rad

    @property
    def angle_max_rad(self) -> float:
        return 0.5 * self.field_of_view_rad

    def beam_angles_rad(self) -> np.ndarray:
        """Beam angles in the scanner frame, increasing (counter-clockwise)."""
        return self.angle_min_rad + np.arange(self.beam_count) * self.angle_increment_rad

    def mount_pose(self) -> np.ndarray:
        return np.array([self.mount_x_m, self.mount_y_m, self.mount_yaw_rad])

    def world_pose(self, robot_pose) -> np.ndarray:
        """Scanner pose (x, y, yaw) in the world for a robot at ``robot_pose`` (x, y, heading)."""
        x, y, heading = (float(v) for v in robot_pose)
        c, s = np.cos(heading), np.sin(heading)
        return np.array(
            [
                x + c * self.mount_x_m - s * self.mount_y_m,
                y + s * self.mount_x_m + c * self.mount_y_m,
                heading + self.mount_yaw_rad,
            ]
        )

    def noise_sigma_m(self, range_m: np.ndarray) -> np.ndarray:
        range_m = np.asarray(range_m, dtype=float)
        return np.where(range_m < self.noise_switch_range_m, self.noise_sigma_near_m, self.noise_fraction_far * range_m)

    def measure(self, true_range_m: np.ndarray, rng: np.random.Generator | None = None) -> np.ndarray:
        """Turn exact ranges (inf = no hit) into readings as the driver gives them: noise, then invalid encoding."""
        true_range_m = np.asarray(true_range_m, dtype=float)
        reading = true_range_m.copy()
        if rng is not None:
            hit = np.isfinite(true_range_m)
            reading[hit] += rng.standard_normal(int(hit.sum())) * self.noise_sigma_m(true_range_m[hit])
        invalid = ~np.isfinite(reading) | (reading < self.range_min_m) | (reading > self.range_max_m)
        reading[invalid] = {"inf": np.inf, "nan": np.nan, "zero": 0.0}[self.invalid_encoding]
        return reading


def paper_scanners(**overrides) -> tuple[ScannerModel, ScannerModel]:
    """The paper's pair: URG-04LX at +0.145 m facing forward and at -0.145 m facing backward."""
    return (
        ScannerModel.urg04lx("front", "forward", **overrides),
        ScannerModel.urg04lx("rear", "backward", **overrides),
    )


def sanitize_ranges(ranges_m, range_min_m: float = 0.0, range_max_m: float = np.inf) -> np.ndarray:
    """Readings as any driver gives them -> float array with NaN for every invalid reading.

    Invalid: NaN, ±inf, 0 or anything below ``range_min_m`` (ROS 1 drivers), above ``range_max_m``.
    """
    ranges = np.array(ranges_m, dtype=float, copy=True).reshape(-1)
    with np.errstate(invalid="ignore"):
        bad = ~np.isfinite(ranges) | (ranges <= 0.0) | (ranges < range_min_m) | (ranges > range_max_m)
    ranges[bad] = np.nan
    return ranges


def scan_points(ranges_m: np.ndarray, angles_rad: np.ndarray, pose=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Points (B, 2) of a sanitised scan in the frame where the scanner has ``pose``; NaN rows stay NaN."""
    x, y, yaw = pose
    world_angles = angles_rad + yaw
    return np.stack([x + ranges_m * np.cos(world_angles), y + ranges_m * np.sin(world_angles)], axis=-1)
