"""Laser perception for the simulator: two simulated scanners -> detections -> world-frame tracks.

Source: paper §1.2 and §4.1 (two 240° URG-04LX, forward and backward, 0.145 m from the centre),
docs/design.md §3. Each ``observe`` call is one 10 Hz cycle: cast both scans at the robot pose, detect round
obstacles in the robot frame (:mod:`~viapath.perception.detection`), move the detections into the
world frame with the robot pose (odometry: the simulator's true pose) and run the tracker
(:mod:`~viapath.perception.tracking`). The planner receives the confirmed tracks.

What we chose:
* Range noise on by default (``range_noise=True``), drawn from the generator given to ``reset``.
* The detector's radius prior is the usual simulated obstacle (0.25 m); ``fixed_radius_m`` switches
  to a known-radius fit (more accurate when every obstacle has the same, known size).
* The planner gets what the tracker reports: the confirmed tracks and the tentative ones within the
  tracker's ``report_tentative_within_m`` of the robot and clear of the static geometry the scans showed
  up to last cycle (:mod:`~viapath.perception.tracking`); a
  confirmed track that is occluded keeps being reported (coasting, with growing sigmas) until
  ``max_unseen_s``.
* Every return no track explains is static geometry (:mod:`~viapath.perception.static_layer`, option
  ``static_layer``), handed to the planner as the observation's static layer. A track that has stood
  still for the tracker's ``static_after_s`` explains nothing and is not reported: a box the detector
  took for a person is kept clear of as a box (:mod:`~viapath.perception.tracking`).
* ``position_noise_m`` / ``velocity_noise_mps`` are oracle options; they are accepted (a scenario's
  ``perception:`` block may carry them) and must be 0 / absent: the laser chain makes its own noise.
"""

from __future__ import annotations

import time
from dataclasses import fields, replace
from typing import Any

import numpy as np

from viapath.observation import Obstacles
from viapath.perception.base import Perception, WorldSnapshot
from viapath.perception.detection import RETIRED_LASER_OPTIONS, Detections, DetectorParams, detect
from viapath.perception.fusion import BlindRegion, blind_region
from viapath.perception.raycast import simulate_scans
from viapath.perception.scanner import ScannerModel, paper_scanners
from viapath.perception.segmentation import SegmentationParams
from viapath.perception.static_layer import StaticLayerParams, StaticObstacleLayer
from viapath.perception.tracking import MultiTargetTracker, Track, TrackerParams
from viapath.static import StaticLayer


def _dataclass_from(cls, value, what: str):
    if value is None:
        return cls()
    if isinstance(value, cls):
        return value
    if not isinstance(value, dict):
        raise TypeError(f"{what} must be a mapping or {cls.__name__}, got {type(value).__name__}")
    value = RETIRED_LASER_OPTIONS.drop(value, what, stacklevel=3)
    names = {f.name for f in fields(cls)}
    unknown = sorted(set(value) - names)
    if unknown:
        raise ValueError(f"{what}: unknown option(s) {', '.join(unknown)}; known: {', '.join(sorted(names))}")
    return cls(**value)


class LaserPerception(Perception):
    """Simulated 360° laser perception (two scanners) with detection and Kalman tracking."""

    name = "laser"

    def __init__(
        self,
        scanners=None,
        detector=None,
        tracker=None,
        *,
        range_noise: bool = True,
        fixed_radius_m: float | None = None,
        robot_radius_m: float = 0.25,
        mode: str | None = None,
        position_noise_m: float | None = None,
        velocity_noise_mps: float | None = None,
        static_layer=None,
        **retired: Any,
    ):
        unknown = set(RETIRED_LASER_OPTIONS.drop(retired, "LaserPerception", stacklevel=3))
        if unknown:
            raise TypeError(f"LaserPerception got unexpected keyword argument(s) {', '.join(sorted(unknown))}")
        if mode not in (None, "laser"):
            raise ValueError(f"LaserPerception got mode={mode!r}")
        for name, value in (("position_noise_m", position_noise_m), ("velocity_noise_mps", velocity_noise_mps)):
            if value not in (None, 0, 0.0):
                raise ValueError(f"{name} is an oracle option; laser perception makes its own noise (range_noise)")
        if scanners is None:
            scanners = paper_scanners()
        self.scanners: tuple[ScannerModel, ...] = tuple(
            s if isinstance(s, ScannerModel) else _dataclass_from(ScannerModel, s, "scanner") for s in scanners
        )
        if not self.scanners:
            raise ValueError("at least one scanner is needed")
        if isinstance(detector, dict) and isinstance(detector.get("segmentation"), dict):
            detector = {
                **detector,
                "segmentation": _dataclass_from(SegmentationParams, detector["segmentation"], "segmentation"),
            }
        if detector is None:
            detector = DetectorParams(keep_segments=False)  # per-segment details cost time; ask for them explicitly
        self.detector_params: DetectorParams = _dataclass_from(DetectorParams, detector, "detector")
        if fixed_radius_m is not None:
            self.detector_params = replace(self.detector_params, fixed_radius_m=float(fixed_radius_m))
        self.tracker_params: TrackerParams = _dataclass_from(TrackerParams, tracker, "tracker")
        self.range_noise = bool(range_noise)
        self.robot_radius_m = float(robot_radius_m)
        self.blind_region: BlindRegion = blind_region(self.scanners, self.robot_radius_m)
        self.rng = np.random.default_rng(0)
        self._tracker = MultiTargetTracker(self.tracker_params)
        self._static = StaticObstacleLayer(
            self.scanners, _dataclass_from(StaticLayerParams, static_layer, "static_layer")
        )
        self._clear()

    def _clear(self) -> None:
        self._tracker.reset()
        self._static.reset()
        self.last_static = StaticLayer.empty()
        self.last_scans: list[np.ndarray] = []
        self.last_points_world = np.zeros((0, 2))
        self.last_detections_world = Detections.empty()
        self.last_robot_pose = np.zeros(3)
        self._reported: list[Obstacles] = []
        self._truth: list[WorldSnapshot] = []
        self._process_times_s: list[float] = []

    def reset(self, rng: np.random.Generator) -> None:
        self.rng = rng
        self._clear()

    # -- what the plots draw ---------------------------------------------------------------------
    @property
    def blind_sectors(self) -> list[tuple[float, float]]:
        """Robot-frame directions (start, end) in which the region no scanner sees reaches beyond the body."""
        return self.blind_region.sectors_rad

    def blind_polygon_world(self, far_m: float = 1.0) -> np.ndarray:
        """The unseen region around the robot at its last pose (closed polygon, world frame)."""
        return self.blind_region.polygon_world(self.last_robot_pose, far_m)

    @property
    def tracks(self) -> list[Track]:
        """Every live track (tentative ones too), world frame."""
        return self._tracker.tracks()

    @property
    def tracker(self) -> MultiTargetTracker:
        return self._tracker

    # -- one cycle -------------------------------------------------------------------------------
    def scan(self, world: WorldSnapshot) -> list[np.ndarray]:
        """The readings of every scanner at the snapshot, as the drivers would report them."""
        pose = np.asarray(world.robot_pose, dtype=float)
        rng = self.rng if self.range_noise else None
        return simulate_scans(self.scanners, pose, world.obstacle_positions, world.obstacle_radii_m, world.walls, rng)

    def process(self, time_s: float, robot_pose, scans) -> Obstacles:
        """Detection and tracking on given scans (no ray casting): the part a real robot runs."""
        robot_pose = np.asarray(robot_pose, dtype=float)
        self.last_robot_pose = robot_pose
        self.last_scans = scans
        detections = detect(self.scanners, scans, self.detector_params)
        self.last_points_world = detections.fused.to_world(robot_pose)  # type: ignore[union-attr]  # scans given
        detections = detections.transformed(robot_pose)
        self.last_detections_world = detections
        tracker = self._tracker
        tracker.step(time_s, detections.centres, detections.position_sigma_m, detections.radii_m)
        known = self.last_static  # the static geometry the scans showed up to last cycle
        self.last_static = self._static.update(time_s, robot_pose, scans, *tracker.explaining())
        return tracker.people(robot_pose[:2], known).finite()

    def static_layer(self, world: WorldSnapshot) -> StaticLayer:
        """What the last scans show of static geometry (:mod:`.static_layer`), not the world's map."""
        return self.last_static

    def observe(self, world: WorldSnapshot) -> Obstacles:
        scans = self.scan(world)
        started = time.perf_counter()
        obstacles = self.process(world.time_s, world.robot_pose, scans)
        self._process_times_s.append(time.perf_counter() - started)
        self._reported.append(obstacles)
        self._truth.append(world)
        return obstacles

    def episode_metrics(self) -> dict:
        """Tracking errors against the truth seen so far (the loop merges these into its metrics)."""
        metrics = tracking_errors(self._reported, self._truth)
        times_ms = np.asarray(self._process_times_s) * 1e3
        metrics["perception_time_p50_ms"] = float(np.percentile(times_ms, 50)) if len(times_ms) else None
        metrics["perception_time_p99_ms"] = float(np.percentile(times_ms, 99)) if len(times_ms) else None
        return metrics


def tracking_errors(reported, truth, match_distance_m: float = 1.0) -> dict:
    """Position and velocity RMSE of reported tracks against the true obstacles (nearest truth).

    ``reported``: one :class:`Obstacles` per cycle; ``truth``: the matching :class:`WorldSnapshot`.
    A reported track is compared with the nearest present true obstacle of its cycle; one farther
    than ``match_distance_m`` is a false track (counted, not in the RMSE). NaN when nothing matched.
    """
    position_sq, velocity_sq = [], []
    false_tracks = 0
    for obstacles, world in zip(reported, truth, strict=True):
        if len(obstacles) == 0:
            continue
        present = world.present()
        true_positions = world.obstacle_positions[present]
        true_velocities = world.obstacle_velocities[present]
        if len(true_positions) == 0:
            false_tracks += len(obstacles)
            continue
        offset = obstacles.positions[:, None, :] - true_positions[None, :, :]
        distance = np.hypot(offset[..., 0], offset[..., 1])
        nearest = distance.argmin(axis=1)
        d = distance[np.arange(len(obstacles)), nearest]
        ok = d <= match_distance_m
        false_tracks += int((~ok).sum())
        position_sq.extend(d[ok] ** 2)
        dv = obstacles.velocities[ok] - true_velocities[nearest[ok]]
        velocity_sq.extend((dv**2).sum(axis=1))
    n = len(position_sq)
    return {
        "track_position_rmse_m": float(np.sqrt(np.mean(position_sq))) if n else float("nan"),
        "track_velocity_rmse_mps": float(np.sqrt(np.mean(velocity_sq))) if n else float("nan"),
        "track_samples": n,
        "false_track_samples": false_tracks,
    }
