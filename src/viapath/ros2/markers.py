"""What the planner saw, as a ``visualization_msgs/MarkerArray`` built from plain arrays.

Source: DESIGN §8 (markers: corridor, tracks, forecasts, via points, plan) and §9 (the paper's
Fig. 4: people as oblique cylinders in x-y-t, time as the height). :func:`scene_from_cycle` turns a
cycle of :class:`~viapath.ros2.core.PlannerCore` into plain arrays; :func:`marker_array` turns plain
arrays into messages, so a later shared scene description can feed it unchanged.

What we chose:
* Namespaces ``corridor``, ``path``, ``tracks`` (one CYLINDER per track, id = track id),
  ``velocities`` (ARROW), ``forecasts`` (one LINE_LIST per track: its disc at t = 0, 1, … 4 s, drawn
  at height ``time_scale_m_per_s`` · t, with the generator lines between), ``via_points`` (SPHERE_LIST),
  ``plan`` (LINE_STRIP of the chosen polyline), ``candidates`` (LINE_LIST, when the planner kept them).
* Every marker is re-published each cycle with ``DELETEALL`` first, so vanished tracks disappear.
* Track markers carry the track id in ``id`` and the scan stamp in the header: tests read tracks back
  from them.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class Scene:
    """Plain arrays of one cycle (world frame, metres, seconds)."""

    corridor_left: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    corridor_right: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    path: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    track_ids: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    track_positions: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    track_velocities: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    track_radii_m: np.ndarray = field(default_factory=lambda: np.zeros(0))
    forecast_times_s: np.ndarray = field(default_factory=lambda: np.arange(0.0, 4.01, 1.0))
    via_points: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    plan: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    candidates: list = field(default_factory=list)


def corridor_edges(path) -> tuple[np.ndarray, np.ndarray]:
    """Left and right corridor edges of a :class:`~viapath.path.DesignatedPath` (offset per segment)."""
    starts, directions = path.segment_starts, path.segment_directions
    ends = starts + directions * path.segment_lengths_m[:, None]
    normals = np.stack([-directions[:, 1], directions[:, 0]], axis=1)
    widths = np.asarray(path.half_widths_m, dtype=float).reshape(-1)
    widths = np.broadcast_to(widths, (len(starts),))
    left = np.concatenate([np.stack([s + n * w, e + n * w]) for s, e, n, w in zip(starts, ends, normals, widths, strict=True)])
    right = np.concatenate([np.stack([s - n * w, e - n * w]) for s, e, n, w in zip(starts, ends, normals, widths, strict=True)])
    return left, right


def scene_from_cycle(path, result) -> Scene:
    """Plain arrays from a :class:`~viapath.ros2.core.CycleResult` and the designated path (or None)."""
    scene = Scene()
    if path is not None:
        scene.corridor_left, scene.corridor_right = corridor_edges(path)
        scene.path = np.asarray(path.waypoints, dtype=float)
    o = result.obstacles
    scene.track_ids, scene.track_positions, scene.track_velocities, scene.track_radii_m = o.ids, o.positions, o.velocities, o.radii_m
    if result.decision is not None:
        plan = result.decision.plan
        scene.via_points = np.asarray(plan.via_points, dtype=float).reshape(-1, 2)
        scene.plan = np.asarray(plan.waypoints, dtype=float).reshape(-1, 2)
        scene.candidates = [np.asarray(c, dtype=float).reshape(-1, 2) for c in plan.candidate_polylines]
    return scene


def _points(msg_cls, xy, z=None) -> list:
    """Points from an (N, 2) or (N, 3) array (one constructor call per point: the cost of a marker)."""
    xy = np.asarray(xy, dtype=float)
    if xy.shape[-1] == 2:
        zs = np.zeros(len(xy)) if z is None else np.broadcast_to(z, (len(xy),))
        xy = np.column_stack([xy, zs])
    return [msg_cls(x=x, y=y, z=z) for x, y, z in xy.tolist()]


_CIRCLE = np.linspace(0.0, 2 * np.pi, 13)


def _forecast_segments(p, v, r, times, time_scale):
    """Endpoints (2S, 3) of the line segments drawing a disc moving at ``v``: rings at ``times`` and 4 generators."""
    rings = np.stack([np.column_stack([p[0] + v[0] * t + r * np.cos(_CIRCLE), p[1] + v[1] * t + r * np.sin(_CIRCLE),
                                       np.full(len(_CIRCLE), t * time_scale)]) for t in times])  # (T, C, 3)
    ring_segments = np.stack([rings[:, :-1], rings[:, 1:]], axis=2).reshape(-1, 3)
    k = [0, 3, 6, 9]
    generators = np.stack([rings[:-1, k], rings[1:, k]], axis=2).reshape(-1, 3)
    return np.concatenate([ring_segments, generators])


def marker_array(scene: Scene, frame_id: str, stamp, time_scale_m_per_s: float = 0.2):
    """The :class:`Scene` as a ``visualization_msgs/MarkerArray`` (``stamp``: a ``builtin_interfaces/Time``)."""
    from geometry_msgs.msg import Point
    from visualization_msgs.msg import Marker, MarkerArray

    out = MarkerArray()
    clear = Marker()
    clear.action = Marker.DELETEALL
    out.markers.append(clear)

    def marker(ns: str, mid: int, kind: int, rgba, scale=(0.03, 0.03, 0.03)) -> Marker:
        m = Marker()
        m.header.frame_id = frame_id
        m.header.stamp = stamp
        m.ns, m.id, m.type, m.action = ns, int(mid), kind, Marker.ADD
        m.pose.orientation.w = 1.0
        m.scale.x, m.scale.y, m.scale.z = (float(v) for v in scale)
        m.color.r, m.color.g, m.color.b, m.color.a = (float(v) for v in rgba)
        out.markers.append(m)
        return m

    for k, edge in enumerate((scene.corridor_left, scene.corridor_right)):
        if len(edge):
            marker("corridor", k, Marker.LINE_LIST, (0.2, 0.4, 1.0, 0.8)).points = _points(Point, edge)
    if len(scene.path):
        marker("path", 0, Marker.LINE_STRIP, (0.2, 0.4, 1.0, 0.4), (0.02, 0.02, 0.02)).points = _points(Point, scene.path)
    for tid, p, v, r in zip(scene.track_ids.tolist(), scene.track_positions, scene.track_velocities,
                            scene.track_radii_m.tolist(), strict=True):
        m = marker("tracks", tid, Marker.CYLINDER, (1.0, 0.5, 0.0, 0.8), (2 * r, 2 * r, 0.1))
        m.pose.position = Point(x=float(p[0]), y=float(p[1]), z=0.05)
        marker("velocities", tid, Marker.ARROW, (1.0, 0.2, 0.0, 1.0), (0.03, 0.06, 0.06)).points = _points(Point, [p, p + v])
        f = marker("forecasts", tid, Marker.LINE_LIST, (1.0, 0.5, 0.0, 0.4), (0.01, 0.01, 0.01))
        f.points = _points(Point, _forecast_segments(p, v, r, scene.forecast_times_s, time_scale_m_per_s))
    if len(scene.via_points):
        marker("via_points", 0, Marker.SPHERE_LIST, (0.9, 0.0, 0.9, 1.0), (0.1, 0.1, 0.1)).points = _points(Point, scene.via_points)
    if len(scene.plan) >= 2:
        marker("plan", 0, Marker.LINE_STRIP, (0.0, 0.8, 0.2, 1.0), (0.04, 0.04, 0.04)).points = _points(Point, scene.plan)
    if scene.candidates:
        segments = [np.stack([c[:-1], c[1:]], axis=1).reshape(-1, 2) for c in scene.candidates if len(c) >= 2]
        if segments:
            marker("candidates", 0, Marker.LINE_LIST, (0.5, 0.5, 0.5, 0.3), (0.01, 0.01, 0.01)).points = _points(
                Point, np.concatenate(segments))
    return out


def tracks_from_markers(markers) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(ids, positions (N, 2), velocities (N, 2)) back from a MarkerArray of :func:`marker_array`."""
    ids, positions, velocities = [], [], []
    arrows = {m.id: m for m in markers.markers if m.ns == "velocities"}
    for m in markers.markers:
        if m.ns == "tracks":
            ids.append(m.id)
            positions.append((m.pose.position.x, m.pose.position.y))
            a = arrows.get(m.id)
            velocities.append((a.points[1].x - a.points[0].x, a.points[1].y - a.points[0].y) if a else (np.nan, np.nan))
    return np.array(ids, dtype=int), np.array(positions, dtype=float).reshape(-1, 2), np.array(velocities, dtype=float).reshape(-1, 2)
