"""The static layer of laser perception: every scan return no person track explains (DESIGN §10).

Source: DESIGN §10; the obstacle layer of a local costmap (ROS navigation: marking by returns, clearing
by the free space along each beam, a memory for what is out of view). What is ours:

* **Marking.** A return is a person's when it lies within the track's radius + ``explained_margin_m``
  of a track (tentative tracks included: a person seen for the first time is not a wall; tracks standing
  still are not passed in, :meth:`~viapath.perception.tracking.MultiTargetTracker.explaining`). Every
  other valid return is static geometry, whatever the detector made of its segment (walls, boxes, legs
  it rejected).
* **Shape.** The returns of one scanner that are neighbours in the scan (consecutive valid beams) and
  less than ``link_m`` apart form a run; each run becomes a polyline through one return about every
  ``step_m`` of its length (:func:`thin_runs`, linear time, unlike Douglas–Peucker, which splits at every
  return once range noise exceeds its tolerance), each segment with the largest distance of the returns
  it skips as its radius (:class:`viapath.static.StaticLayer.radii_m`): the polyline never brings the
  robot nearer to a return than its margins allow. A run of one return is a point. Runs (and remembered
  pieces) within ``merge_gap_m`` of each other are one shape (:func:`viapath.static.merge_close_shapes`):
  the planner goes round shapes, and two scanners' views of one box are one box.
* **Memory.** Last cycle's layer is kept, in the world frame (moved with odometry like the tracks), for
  what the scanners do not show now: a remembered segment whose ends and middle are all seen by the new
  scans, i.e. a beam in that direction reaches at least that far (the return is there again, and the
  new run holds it; or the beam passes it: gone), is dropped; one that some point of it is hidden
  (a nearer return in front of it, an invalid reading, a return there that only a tentative track
  explains: the detector starts tentative tracks on the corners of boxes and carts, and one must not take
  a box the layer knows out of it where the robot is nearest to it) is kept, up to ``memory_s`` after it was last
  part of a scan. One that some point of it lies outside every scanner's field of view (the blind
  sectors beside the body, the field of a silent scanner) is kept, however old, until the scans show
  it again: no beam can clear it, and it is where a turning robot meets it (a robot that stood beside
  a box for longer than ``memory_s`` would otherwise forget the box's side in its blind sector). What
  lies beyond every scanner's range is forgotten.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from viapath.perception.scanner import ScannerModel
from viapath.static import StaticLayer, merge_close_shapes


@dataclass(frozen=True)
class StaticLayerParams:
    enabled: bool = True
    explained_margin_m: float = 0.15  # a return this close to a track's disc is the person's
    link_m: float = 0.2  # neighbouring returns closer than this are one run
    step_m: float = 0.15  # a run of returns becomes a polyline through one return about this far apart
    memory_s: float = 2.0  # how long geometry out of view is remembered
    see_through_m: float = 0.05  # a beam that reaches within this of a remembered point sees it
    merge_gap_m: float = 0.6  # runs closer than this are one shape to go round (no robot fits between)

    def __post_init__(self) -> None:
        for name in ("explained_margin_m", "link_m", "step_m", "memory_s", "see_through_m", "merge_gap_m"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise ValueError(f"static_layer.{name}: expected a finite number >= 0, found {value!r}")


def thin_runs(points: np.ndarray, run: np.ndarray, step_m: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Polylines through runs of returns (``run``: (P,) non-decreasing run number of each point): each run's
    returns where its length passes a multiple of ``step_m``, and its last one. Returns the segments (S, 2, 2),
    the run of each, and each segment's radius: the largest distance of the returns it stands for from it,
    so that the polylines with their radii cover every return. A run of one return is a segment of length 0."""
    count = len(points)
    first = np.flatnonzero(np.diff(run, prepend=-1) != 0)  # where each run starts
    last = np.append(first[1:], count) - 1
    step = np.zeros(count)
    step[1:] = np.hypot(*np.diff(points, axis=0).T)
    step[first] = 0.0
    along = np.cumsum(step)
    along -= np.repeat(along[first], np.diff(np.append(first, count)))
    bucket = np.floor(along / step_m).astype(np.int64)
    keep = np.zeros(count, dtype=bool)
    keep[first] = keep[last] = True
    keep[1:] |= (bucket[1:] != bucket[:-1]) & (run[1:] == run[:-1])
    kept = np.flatnonzero(keep)
    # Segments join consecutive kept returns of one run; a run of one return is a point.
    joined = run[kept[1:]] == run[kept[:-1]]
    starts, ends = kept[:-1][joined], kept[1:][joined]
    single = first[first == last]
    segment_starts = np.concatenate([starts, single])
    segment_ends = np.concatenate([ends, single])
    order = np.argsort(segment_starts, kind="stable")
    segment_starts, segment_ends = segment_starts[order], segment_ends[order]
    segments = np.stack([points[segment_starts], points[segment_ends]], axis=1)
    # Each return belongs to the segment that starts at the last kept return at or before it (a run's last
    # return to the segment that ends there).
    owner = np.searchsorted(segment_starts, np.arange(count), side="right") - 1
    at_end = np.isin(np.arange(count), last) & ~np.isin(np.arange(count), single)
    owner[at_end] = np.searchsorted(segment_ends, np.arange(count)[at_end], side="left")
    a, b = segments[owner, 0], segments[owner, 1]
    d = b - a
    length2 = np.einsum("ij,ij->i", d, d)
    t = np.clip(np.einsum("ij,ij->i", points - a, d) / np.where(length2 > 0, length2, 1.0), 0.0, 1.0)
    deviation = np.hypot(*(points - a - t[:, None] * d).T)
    radii = np.zeros(len(segments))
    np.maximum.at(radii, owner, deviation)
    return segments, run[segment_starts], radii


class StaticObstacleLayer:
    """Turns each cycle's scans into a :class:`~viapath.static.StaticLayer` in the world frame."""

    def __init__(self, scanners: tuple[ScannerModel, ...], params: StaticLayerParams | None = None):
        self.scanners = tuple(scanners)
        self.params = params or StaticLayerParams()
        self.reset()

    def reset(self) -> None:
        self.layer = StaticLayer.empty()
        self._seen_s = np.zeros(0)  # when each remembered segment was last part of a scan

    def update(
        self,
        time_s: float,
        robot_pose,
        scans,
        track_positions: np.ndarray,
        track_radii_m: np.ndarray,
        track_confirmed: np.ndarray | None = None,
        scanners=None,
    ) -> StaticLayer:
        """This cycle's layer; ``track_confirmed``: which tracks are confirmed (None: all);
        ``scanners``: the models of ``scans`` when not all of this layer's (a silent scanner's scan missing)."""
        if not self.params.enabled:
            return StaticLayer.empty()
        pose = np.asarray(robot_pose, dtype=float)
        scanners = self.scanners if scanners is None else tuple(scanners)
        confirmed = np.ones(len(track_radii_m), dtype=bool) if track_confirmed is None else np.asarray(track_confirmed)
        current, tentative_beams = self._from_scans(scanners, pose, scans, track_positions, track_radii_m, confirmed)
        kept = self._remembered(scanners, time_s, pose, scans, tentative_beams)
        layer = merge_close_shapes(current.concatenate(kept), self.params.merge_gap_m)
        self._seen_s = np.concatenate([np.full(len(current), float(time_s)), self._seen_s[self._kept_rows]])
        self.layer = layer
        return layer

    # -- marking ---------------------------------------------------------------------------------

    def _from_scans(
        self, scanners, pose: np.ndarray, scans, track_positions, track_radii_m, confirmed: np.ndarray
    ) -> tuple[StaticLayer, list[np.ndarray]]:
        """The static geometry of this cycle's scans, and per scan the beams whose return only a tentative
        track explains."""
        p = self.params
        tentative: list[np.ndarray] = []
        segments: list[Any] = []
        runs: list[Any] = []
        radii: list[Any] = []
        for index, (scanner, ranges) in enumerate(zip(scanners, scans, strict=True)):
            ranges = np.asarray(ranges, dtype=float).reshape(-1)
            tentative_beams = np.zeros(scanner.beam_count, dtype=bool)
            tentative.append(tentative_beams)
            if len(ranges) != scanner.beam_count:
                continue
            with np.errstate(invalid="ignore"):
                valid = (
                    np.isfinite(ranges) & (ranges >= max(scanner.range_min_m, 1e-9)) & (ranges <= scanner.range_max_m)
                )
            beams = np.flatnonzero(valid)
            if len(beams) == 0:
                continue
            x, y, yaw = scanner.world_pose(pose)
            angles = scanner.beam_angles_rad()[beams] + yaw
            points = np.stack([x + ranges[beams] * np.cos(angles), y + ranges[beams] * np.sin(angles)], axis=1)
            if len(track_positions):
                offset = points[:, None, :] - np.asarray(track_positions)[None]
                distance = np.hypot(offset[..., 0], offset[..., 1])
                near = distance <= np.asarray(track_radii_m)[None] + p.explained_margin_m
                explained = near.any(axis=1)
                tentative_beams[beams[explained & ~near[:, confirmed].any(axis=1)]] = True
                points, beams = points[~explained], beams[~explained]
            for earlier, earlier_ranges in zip(scanners[:index], scans[:index]):
                # Where an earlier scanner returned the same point, its run has it already.
                again = self._returned_by(earlier, pose, np.asarray(earlier_ranges, dtype=float).reshape(-1), points)
                points, beams = points[~again], beams[~again]
            if len(points) == 0:
                continue
            gap = np.hypot(*np.diff(points, axis=0).T) if len(points) > 1 else np.zeros(0)
            run = np.concatenate([[0], np.cumsum((np.diff(beams) != 1) | (gap > p.link_m))])
            pieces, piece_runs, piece_radii = thin_runs(points, run, p.step_m)
            segments.append(pieces)
            runs.append(piece_runs + (runs[-1].max() + 1 if runs else 0))
            radii.append(piece_radii)
        if not segments:
            return StaticLayer.empty(), tentative
        return StaticLayer(np.concatenate(segments), np.concatenate(runs), np.concatenate(radii)), tentative

    # -- memory ----------------------------------------------------------------------------------

    def _remembered(self, scanners, time_s: float, pose: np.ndarray, scans, tentative_beams) -> StaticLayer:
        previous = self.layer
        self._kept_rows = np.zeros(0, dtype=int)
        if len(previous) == 0:
            return StaticLayer.empty()
        young = time_s - self._seen_s <= self.params.memory_s + 1e-9
        a, b = previous.segments[:, 0], previous.segments[:, 1]
        probes = np.stack([a, 0.5 * (a + b), b], axis=1).reshape(-1, 2)  # (3M, 2)
        seen = np.zeros(len(probes), dtype=bool)
        for scanner, ranges, tentative in zip(scanners, scans, tentative_beams, strict=True):
            seen |= self._seen_by(scanner, pose, np.asarray(ranges, dtype=float).reshape(-1), probes, tentative)
        beyond = np.ones(len(probes), dtype=bool)  # beyond every scanner's range: not worth remembering
        in_view = np.zeros(len(probes), dtype=bool)
        for scanner in scanners:
            x, y, _ = scanner.world_pose(pose)
            beyond &= np.hypot(probes[:, 0] - x, probes[:, 1] - y) > scanner.range_max_m
            in_view |= self._beams_to(scanner, pose, probes)[0]
        hidden = ~(seen | beyond).reshape(-1, 3).all(axis=1)
        out_of_view = (~(in_view | beyond)).reshape(-1, 3).any(axis=1)
        rows = np.flatnonzero(hidden & (young | out_of_view))
        self._kept_rows = rows
        return previous.subset(rows)

    @staticmethod
    def _beams_to(scanner: ScannerModel, pose: np.ndarray, points: np.ndarray):
        """For each point: whether it is in the scanner's field of view and range, its distance, and the
        beam towards it (clipped to the scan)."""
        x, y, yaw = scanner.world_pose(pose)
        offset = points - (x, y)
        distance = np.hypot(offset[:, 0], offset[:, 1])
        bearing = (np.arctan2(offset[:, 1], offset[:, 0]) - yaw + np.pi) % (2 * np.pi) - np.pi
        beam = np.rint((bearing - scanner.angle_min_rad) / scanner.angle_increment_rad).astype(np.int64)
        inside = (beam >= 0) & (beam < scanner.beam_count) & (distance <= scanner.range_max_m)
        return inside, distance, np.clip(beam, 0, scanner.beam_count - 1)

    def _returned_by(
        self, scanner: ScannerModel, pose: np.ndarray, ranges: np.ndarray, points: np.ndarray
    ) -> np.ndarray:
        """Whether the scan's beam towards each point returned from there (within ``see_through_m``)."""
        if len(ranges) != scanner.beam_count or len(points) == 0:
            return np.zeros(len(points), dtype=bool)
        inside, distance, beam = self._beams_to(scanner, pose, points)
        with np.errstate(invalid="ignore"):
            return inside & (np.abs(ranges[beam] - distance) <= self.params.see_through_m)

    def _seen_by(
        self, scanner: ScannerModel, pose: np.ndarray, ranges: np.ndarray, points: np.ndarray, tentative: np.ndarray
    ) -> np.ndarray:
        """Whether a beam of this scan reaches each point (its reading at least the point's range, less
        ``see_through_m``; +inf or a reading past the range limit: the beam is free to the limit), a return
        at the point that only a tentative track explains (``tentative``, per beam) excepted."""
        if len(ranges) != scanner.beam_count:
            return np.zeros(len(points), dtype=bool)
        inside, distance, beam = self._beams_to(scanner, pose, points)
        reading = ranges[beam]
        with np.errstate(invalid="ignore"):
            unconfirmed_return_there = tentative[beam] & (reading <= distance + self.params.see_through_m)
            free = (reading == np.inf) | (reading > scanner.range_max_m)
            reaches = (
                np.isfinite(reading)
                & (reading >= scanner.range_min_m)
                & (reading > 0)
                & (reading >= distance - self.params.see_through_m)
            )
        return inside & (free | reaches) & ~unconfirmed_return_there
