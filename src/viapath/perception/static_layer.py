"""The static layer of laser perception: every scan return no person track explains (docs/design.md §10).

Source: docs/design.md §10; the obstacle layer of a local costmap (ROS navigation: marking by returns, clearing
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
  robot nearer to a return than its margins allow. A run of one return is a point. The marking and the
  thinning are compiled loops over the returns (:func:`viapath.jit.compiled`; plain Python when compilation
  is off); the returns' positions and bearings are numpy's (``np.cos``, ``np.arctan2``). Runs (and remembered
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

from viapath.jit import compiled
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
    points = np.ascontiguousarray(points, dtype=float).reshape(-1, 2)
    run = np.ascontiguousarray(run, dtype=np.int64)
    starts, ends = np.empty(len(points), np.int64), np.empty(len(points), np.int64)
    radii = np.empty(len(points))
    count = _thin(points, run, float(step_m), starts, ends, radii)
    starts, ends = starts[:count], ends[:count]
    return np.stack([points[starts], points[ends]], axis=1), run[starts], radii[:count].copy()


@compiled
def _thin(points, run, step_m, starts, ends, radii):
    """:func:`thin_runs`: fills the first and last return of each segment (in order) and its radius; returns the
    number of segments. A return belongs to the segment that starts at the last kept return at or before it, a
    run's last return to the segment that ends there."""
    count = points.shape[0]
    segments = 0
    along = 0.0  # the length of the returns' polyline, every run after the other
    run_start = 0.0  # ``along`` at the current run's first return
    bucket = 0.0
    kept = 0  # the last kept return of the current run
    for i in range(count):
        first = i == 0 or run[i] != run[i - 1]
        last = i == count - 1 or run[i + 1] != run[i]
        if first:
            run_start = along  # the step into a run is not part of its length
            bucket = np.floor((along - run_start) / step_m)
            kept = i
            if last:  # a run of one return: a point
                starts[segments], ends[segments], radii[segments] = i, i, 0.0
                segments += 1
            continue
        along += np.hypot(points[i, 0] - points[i - 1, 0], points[i, 1] - points[i - 1, 1])
        previous, bucket = bucket, np.floor((along - run_start) / step_m)
        if last or bucket != previous:
            starts[segments], ends[segments] = kept, i
            radii[segments] = _largest_deviation(points, kept, i, i + 1 if last else i)
            segments += 1
            kept = i
    return segments


@compiled
def _largest_deviation(points, a, b, stop):
    """The largest distance of ``points[a:stop]`` from the segment from ``points[a]`` to ``points[b]``."""
    dx = points[b, 0] - points[a, 0]
    dy = points[b, 1] - points[a, 1]
    length2 = dx * dx + dy * dy
    if not length2 > 0:
        length2 = 1.0
    largest = 0.0
    for i in range(a, stop):
        rx = points[i, 0] - points[a, 0]
        ry = points[i, 1] - points[a, 1]
        t = min(max((rx * dx + ry * dy) / length2, 0.0), 1.0)
        largest = max(largest, np.hypot(rx - t * dx, ry - t * dy))
    return largest


@compiled
def _explained(points, beams, tracks, reach, confirmed, static, tentative_beams):
    """Which returns (``points``, from ``beams``) are static: those no track explains (within ``reach`` of its
    centre). Marks in ``tentative_beams`` the beams whose return only tentative tracks explain."""
    for i in range(points.shape[0]):
        explained = False
        by_confirmed = False
        for j in range(tracks.shape[0]):
            if np.hypot(points[i, 0] - tracks[j, 0], points[i, 1] - tracks[j, 1]) <= reach[j]:
                explained = True
                by_confirmed = by_confirmed or confirmed[j]
        static[i] = not explained
        if explained and not by_confirmed:
            tentative_beams[beams[i]] = True


@compiled
def _runs(points, beams, link_m, run):
    """The run number of each return of one scan (in beam order): neighbouring beams' returns less than
    ``link_m`` apart are one run."""
    label = 0
    for i in range(points.shape[0]):
        if i > 0:
            gap = np.hypot(points[i, 0] - points[i - 1, 0], points[i, 1] - points[i - 1, 1])
            if beams[i] - beams[i - 1] != 1 or gap > link_m:
                label += 1
        run[i] = label


@compiled
def _look(inside, distance, beam, ranges, tentative, readable, limits, seen):
    """Marks in ``seen`` the points (in the scanner's view: ``inside``, at ``distance`` along ``beam``) that a
    beam of this scan reaches: its reading at least the point's range, less ``see_through``; +inf or a reading
    past the range limit: the beam is free to the limit. A return at the point that only a tentative track
    explains (``tentative``, per beam) does not count. ``limits`` = (range min, range max, see through);
    ``readable``: the scan has the scanner's beam count (else it shows nothing)."""
    range_min, range_max, see_through = limits
    if not readable:
        return
    for i in range(inside.shape[0]):
        if not inside[i]:
            continue
        reading = ranges[beam[i]]
        if tentative[beam[i]] and reading <= distance[i] + see_through:
            continue
        free = reading == np.inf or reading > range_max
        reaches = np.isfinite(reading) and reading >= range_min and reading > 0 and reading >= distance[i] - see_through
        if free or reaches:
            seen[i] = True


def _returns(scanner: ScannerModel, pose: np.ndarray, ranges: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The valid returns of one scan in the world frame (P, 2) and their beams (P,)."""
    with np.errstate(invalid="ignore"):
        valid = np.isfinite(ranges) & (ranges >= max(scanner.range_min_m, 1e-9)) & (ranges <= scanner.range_max_m)
    beams = np.flatnonzero(valid)
    x, y, yaw = scanner.world_pose(pose)
    angles = scanner.beam_angles_rad()[beams] + yaw
    return np.stack([x + ranges[beams] * np.cos(angles), y + ranges[beams] * np.sin(angles)], axis=1), beams


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
        tracks = np.ascontiguousarray(track_positions, dtype=float).reshape(-1, 2)
        reach = np.asarray(track_radii_m, dtype=float).reshape(-1) + p.explained_margin_m
        confirmed = np.ascontiguousarray(confirmed, dtype=bool).reshape(-1)
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
            points, beams = _returns(scanner, pose, ranges)
            static = np.empty(len(beams), dtype=bool)
            _explained(points, beams, tracks, reach, confirmed, static, tentative_beams)
            for earlier, earlier_ranges in zip(scanners[:index], scans[:index]):
                # Where an earlier scanner returned the same point, its run has it already.
                static &= ~self._returned_by(earlier, pose, np.asarray(earlier_ranges, dtype=float).reshape(-1), points)
            points, beams = points[static], beams[static]
            if len(points) == 0:
                continue
            run = np.empty(len(points), dtype=np.int64)
            _runs(points, beams, p.link_m, run)
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
        p = self.params
        young = time_s - self._seen_s <= p.memory_s + 1e-9
        a, b = previous.segments[:, 0], previous.segments[:, 1]
        probes = np.stack([a, 0.5 * (a + b), b], axis=1).reshape(-1, 2)  # (3M, 2)
        seen = np.zeros(len(probes), dtype=bool)  # a beam reaches it
        beyond = np.ones(len(probes), dtype=bool)  # beyond every scanner's range: not worth remembering
        in_view = np.zeros(len(probes), dtype=bool)
        for scanner, ranges, tentative in zip(scanners, scans, tentative_beams, strict=True):
            ranges = np.asarray(ranges, dtype=float).reshape(-1)
            inside, distance, beam = self._beams_to(scanner, pose, probes)
            readable = len(ranges) == scanner.beam_count
            limits = (scanner.range_min_m, scanner.range_max_m, p.see_through_m)
            _look(inside, distance, beam, ranges, tentative, readable, limits, seen)
            beyond &= distance > scanner.range_max_m
            in_view |= inside
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
