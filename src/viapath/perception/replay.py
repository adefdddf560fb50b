"""Run detection and tracking over a recorded scan sequence, and score detections against labels.

Source: the chain of :mod:`~viapath.perception.detection` and :mod:`~viapath.perception.tracking`,
applied to real ``sensor_msgs/LaserScan`` messages (:mod:`viapath.io.rosbag`); the evaluation
protocol for the leg_tracker training bag (Leigh et al., ICRA 2015, data README §4).

What we chose:
* The sensor does not move in these recordings: the world frame is the laser frame (a moving
  sensor needs its odometry pose per scan: ``poses`` argument).
* Real scans use :meth:`DetectorParams.for_legs` and a tracker with ``σ_a = 0.5 m/s²`` (people
  start, stop and turn; leg-derived positions swing with the gait).
* Label evaluation (``positive_2_extracted.bag``): scans and ``PoseArray`` labels are paired by
  message order; the labelled legs of one message are one person at their mean. A person is
  *found* when a detection lies within ``match_distance_m`` (0.35 m: half a stride) of it. Labels
  exist only inside the ±15°, ≤ 5 m wedge, so *precision* counts only detections whose centre is in
  that wedge: each is a true positive if it matches the labelled person (at most one per scan),
  else a false positive. Leg-level recall (a leg-sized detection within 0.15 m of a labelled leg)
  is reported beside it.
* A track's *speed* for the walking-speed statistics is the filtered speed of a confirmed track;
  "walking" tracks are those that moved at least ``min_travel_m`` (1 m, start to end) and whose
  median speed is at least 0.2 m/s — clutter (chair legs, door frames) produces confirmed but
  static tracks, and a static track that once jumps to a passing person is not a walker.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from viapath.perception.detection import Detections, DetectorParams, detect
from viapath.perception.tracking import MultiTargetTracker, TrackerParams

REAL_SCAN_TRACKER = TrackerParams(acceleration_sigma_mps2=0.5)


@dataclass
class RecordingResult:
    """Per scan: time and detections; per confirmed track and scan: one row of ``track_rows``."""

    times_s: np.ndarray  # (S,) scan stamps, seconds since the first scan
    start_stamp_s: float
    detections: list[Detections]
    track_rows: np.ndarray  # (R, 9): scan index, time_s, id, x, y, vx, vy, radius, position_sigma
    velocity_sigma_mps: np.ndarray  # (R,)
    points: list[np.ndarray] = field(default_factory=list)  # valid scan points per scan (sensor frame)

    COLUMNS = ("scan", "time_s", "track_id", "x_m", "y_m", "vx_mps", "vy_mps", "radius_m", "position_sigma_m")

    def track_ids(self) -> np.ndarray:
        return np.unique(self.track_rows[:, 2]).astype(int) if len(self.track_rows) else np.zeros(0, dtype=int)

    def track(self, track_id: int) -> np.ndarray:
        return self.track_rows[self.track_rows[:, 2] == track_id]

    def track_summary(self, min_travel_m: float = 1.0, min_median_speed_mps: float = 0.2) -> list[dict]:
        """One dict per confirmed track: life, travel, median / mean speed, whether it walked."""
        out = []
        for tid in self.track_ids():
            rows = self.track(tid)
            xy = rows[:, 3:5]
            speed = np.hypot(rows[:, 5], rows[:, 6])
            travel = float(np.hypot(*(xy[-1] - xy[0])))
            out.append(
                dict(
                    track_id=int(tid),
                    first_s=float(rows[0, 1]),
                    last_s=float(rows[-1, 1]),
                    duration_s=float(rows[-1, 1] - rows[0, 1]),
                    scans=len(rows),
                    start_x_m=float(xy[0, 0]),
                    start_y_m=float(xy[0, 1]),
                    end_x_m=float(xy[-1, 0]),
                    end_y_m=float(xy[-1, 1]),
                    travel_m=travel,
                    median_speed_mps=float(np.median(speed)),
                    mean_speed_mps=float(np.mean(speed)),
                    walking=bool(travel >= min_travel_m and np.median(speed) >= min_median_speed_mps),
                )
            )
        return out

    def walking_speeds(self, min_travel_m: float = 1.0) -> np.ndarray:
        """Filtered speeds of all rows of walking tracks (see module notes)."""
        walking = [s["track_id"] for s in self.track_summary(min_travel_m) if s["walking"]]
        rows = self.track_rows[np.isin(self.track_rows[:, 2], walking)] if walking else np.zeros((0, 9))
        return np.hypot(rows[:, 5], rows[:, 6])


def track_recording(
    messages,
    detector: DetectorParams | None = None,
    tracker: TrackerParams | None = None,
    poses=None,
    keep_points: bool = True,
    people_only: bool = False,
) -> RecordingResult:
    """Detect and track over ``messages`` (:class:`~viapath.io.rosbag.LaserScanMessage`, in order).

    ``poses``: optional (S, 3) sensor pose per scan in a fixed world frame (default: a fixed sensor).
    ``people_only``: report the tracks a planner receives (not those standing still,
    :meth:`~viapath.perception.tracking.MultiTargetTracker.people`) instead of every confirmed track.
    """
    detector = detector or DetectorParams.for_legs()
    tracking = MultiTargetTracker(tracker or REAL_SCAN_TRACKER)
    times: list[Any] = []
    detections, rows, vel_sigma, points = [], [], [], []
    start = None
    scanner = None
    for k, message in enumerate(messages):
        if scanner is None or scanner.beam_count != message.beam_count:
            scanner = message.scanner_model()
        start = message.stamp_s if start is None else start
        t = message.stamp_s - start
        if times and t < times[-1]:
            t = times[-1]  # a stamp that jumps back is held (rare driver glitches)
        pose = (0.0, 0.0, 0.0) if poses is None else poses[k]
        found = detect([scanner], [message.ranges_m], detector).transformed(pose)
        tracking.step(t, found.centres, found.position_sigma_m, found.radii_m)
        obstacles = tracking.people() if people_only else tracking.obstacles()
        for i in range(len(obstacles)):
            rows.append(
                (
                    k,
                    t,
                    obstacles.ids[i],
                    *obstacles.positions[i],
                    *obstacles.velocities[i],
                    obstacles.radii_m[i],
                    obstacles.position_sigma_m[i],
                )
            )
            vel_sigma.append(obstacles.velocity_sigma_mps[i])
        times.append(t)
        detections.append(found)
        if keep_points:
            points.append(found.fused.to_world(pose) if found.fused is not None else np.zeros((0, 2)))
    track_rows = np.array(rows, dtype=float).reshape(-1, 9)
    return RecordingResult(np.array(times), float(start or 0.0), detections, track_rows, np.array(vel_sigma), points)


def in_wedge(points: np.ndarray, half_angle_rad: float = np.deg2rad(15.0), max_range_m: float = 5.0) -> np.ndarray:
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    return (np.abs(np.arctan2(points[:, 1], points[:, 0])) <= half_angle_rad) & (
        np.hypot(points[:, 0], points[:, 1]) <= max_range_m
    )


def evaluate_labels(
    detections: list[Detections],
    labels: list[np.ndarray],
    match_distance_m: float = 0.35,
    leg_match_distance_m: float = 0.15,
) -> dict:
    """Recall and precision of person detections against labelled legs (see module notes), paired by order."""
    if len(detections) != len(labels):
        raise ValueError(f"{len(detections)} scans but {len(labels)} label messages: cannot pair by order")
    people = found = true_pos = false_pos = 0
    legs = legs_found = leg_false_pos = 0
    errors = []
    for det, legs_xy in zip(detections, labels, strict=True):
        legs_xy = np.asarray(legs_xy, dtype=float).reshape(-1, 2)
        centres = det.centres
        wedge = in_wedge(centres) if len(centres) else np.zeros(0, dtype=bool)
        if len(legs_xy):
            people += 1
            person = legs_xy.mean(axis=0)
            distance = np.hypot(*(centres - person).T) if len(centres) else np.zeros(0)
            match = distance <= match_distance_m
            if match.any():
                found += 1
                best = int(np.argmin(np.where(match, distance, np.inf)))
                errors.append(distance[best])
                true_pos += 1
                false_pos += int((wedge & (np.arange(len(centres)) != best)).sum())
            else:
                false_pos += int(wedge.sum())
            for leg in legs_xy:
                legs += 1
                if len(det.legs) and np.hypot(*(det.legs - leg).T).min() <= leg_match_distance_m:
                    legs_found += 1
            if len(det.legs):
                near = (
                    np.hypot(*(det.legs[:, None, :] - legs_xy[None]).transpose(2, 0, 1)).min(axis=1)
                    <= leg_match_distance_m
                )
                leg_false_pos += int((in_wedge(det.legs) & ~near).sum())
        else:
            false_pos += int(wedge.sum())
    return {
        "scans": len(detections),
        "labelled_people": people,
        "person_recall": found / people if people else float("nan"),
        "person_precision_in_wedge": true_pos / (true_pos + false_pos) if true_pos + false_pos else float("nan"),
        "false_positives_in_wedge": false_pos,
        "person_position_error_median_m": float(np.median(errors)) if errors else float("nan"),
        "labelled_legs": legs,
        "leg_recall": legs_found / legs if legs else float("nan"),
        "leg_false_positives_in_wedge": leg_false_pos,
        "match_distance_m": match_distance_m,
    }
