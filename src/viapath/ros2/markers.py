"""What the planner saw, as a ``visualization_msgs/MarkerArray`` built from the shared scene.

Source: docs/design.md §8 (markers: corridor, tracks, forecasts, via points, plan) and §9 (the paper's
Fig. 4: people as oblique cylinders in x-y-t, time as the height). The messages are built from a
:class:`viapath.viz.scene.CycleScene`, the neutral description the Foxglove views draw from too, so
RViz and Foxglove show the same forecast: :class:`MarkerScenes` turns a cycle of
:class:`~viapath.ros2.core.PlannerCore` into one (:meth:`MarkerScenes.scene`), :func:`marker_array`
turns it into messages.

What we chose:
* Namespaces ``corridor`` (one LINE_STRIP per segment: the capsule outline of
  :func:`viapath.viz.scene.path_view`), ``path``, ``static`` (one LINE_LIST of the static layer the planner
  was told about), ``tracks`` (one CYLINDER per track, id = track id),
  ``velocities`` (ARROW), ``forecasts`` (one LINE_LIST per track: the scene's x-y-t cylinder, its
  three rings at 0, where the uncertainty cone stops growing, and the horizon, with four generator
  lines between, drawn at height ``time_scale_m_per_s`` · t), ``via_points`` (SPHERE_LIST), ``plan``
  (LINE_STRIP of the chosen polyline), ``candidates`` (LINE_LIST, when the planner kept them).
* Every marker is re-published each cycle with ``DELETEALL`` first, so vanished tracks disappear.
* Track markers carry the track id in ``id`` and the scan stamp in the header: tests read tracks back
  from them.
* A cycle without a planner decision (the node brakes: no scan, no odometry) is drawn as a stop plan
  at the robot: tracks and path still show. Without a designated path there is no scene (the node
  brakes and says why in its diagnostics), so no markers.
"""

from __future__ import annotations

import numpy as np

from viapath.observation import Decision, Observation, Plan, RobotState
from viapath.viz.scene import CycleScene, ForecastSettings, PathView, SceneBuilder

RING_SEGMENTS = 12
GENERATORS = (0, 3, 6, 9)  # ring points joined from ring to ring (four of the twelve)


class MarkerScenes:
    """The node's scene builder: a new one whenever the designated path (and so the planner) changes,
    with the planner's horizon and uncertainty cone for the forecasts."""

    def __init__(self, robot_radius_m: float):
        self.robot_radius_m = float(robot_radius_m)
        self._path = None
        self._builder: SceneBuilder | None = None
        self.step = 0

    def builder(self, path, planner) -> SceneBuilder:
        if self._builder is None or path is not self._path:
            self._path = path
            self._builder = SceneBuilder(path, self.robot_radius_m, ForecastSettings.from_planner(planner))
        return self._builder

    def scene(self, path, planner, result) -> CycleScene:
        """The scene of a :class:`~viapath.ros2.core.CycleResult` on the designated path (not None)."""
        pose = np.asarray(result.robot_pose if result.robot_pose is not None else np.zeros(3), dtype=float)
        decision = result.decision
        if decision is None:
            decision = Decision(result.command, Plan("stop", 0.0, pose[:2].copy()))
        robot = RobotState(pose[:2].copy(), float(pose[2]), 0.0, 0.0, self.robot_radius_m)
        plan_time_ms = result.cycle_time_ms if result.cycle_time_ms is not None else float("nan")
        self.step += 1
        return self.builder(path, planner).build(
            self.step - 1,
            result.stamp_s,
            pose,
            0.0,
            0.0,
            Observation(result.stamp_s, robot, result.obstacles, result.static),
            decision,
            plan_time_ms,
        )


def _points(msg_cls, xyz) -> list:
    """Points from an (N, 2) or (N, 3) array (one constructor call per point: the cost of a marker)."""
    xyz = np.asarray(xyz, dtype=float)
    if xyz.shape[-1] == 2:
        xyz = np.column_stack([xyz, np.zeros(len(xyz))])
    return [msg_cls(x=x, y=y, z=z) for x, y, z in xyz.tolist()]


def forecast_segments(rings: np.ndarray, time_scale_m_per_s: float) -> np.ndarray:
    """Endpoints (2S, 3) of the segments drawing one cylinder from its rings (R, C, 3) in x, y, t:
    each ring closed, and the generator lines between consecutive rings; heights = t · scale."""
    rings = np.asarray(rings, dtype=float) * [1.0, 1.0, time_scale_m_per_s]
    closed = np.concatenate([rings, rings[:, :1]], axis=1)
    ring_segments = np.stack([closed[:, :-1], closed[:, 1:]], axis=2).reshape(-1, 3)
    k = list(GENERATORS)
    generators = np.stack([rings[:-1, k], rings[1:, k]], axis=2).reshape(-1, 3)
    return np.concatenate([ring_segments, generators])


def marker_array(scene: CycleScene, path: PathView | None, frame_id: str, stamp):
    """The scene as a ``visualization_msgs/MarkerArray`` (``stamp``: a ``builtin_interfaces/Time``)."""
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

    if path is not None:
        for k, outline in enumerate(path.corridor_outlines):
            marker("corridor", k, Marker.LINE_STRIP, (0.2, 0.4, 1.0, 0.8)).points = _points(Point, outline)
        marker("path", 0, Marker.LINE_STRIP, (0.2, 0.4, 1.0, 0.4), (0.02, 0.02, 0.02)).points = _points(
            Point, path.waypoints
        )
    if len(scene.static_segments):
        marker("static", 0, Marker.LINE_LIST, (0.1, 0.1, 0.1, 0.9), (0.03, 0.03, 0.03)).points = _points(
            Point, scene.static_segments.reshape(-1, 2)
        )
    tracks = scene.tracks
    scale = scene.xyt.settings.time_scale_m_per_s
    rings = scene.xyt.all_rings(RING_SEGMENTS)  # (P, 3, C, 3), in the order of scene.xyt.persons = tracks
    for i, (tid, p, v, r) in enumerate(
        zip(tracks.ids.tolist(), tracks.positions, tracks.velocities, tracks.radii_m.tolist(), strict=True)
    ):
        m = marker("tracks", tid, Marker.CYLINDER, (1.0, 0.5, 0.0, 0.8), (2 * r, 2 * r, 0.1))
        m.pose.position = Point(x=float(p[0]), y=float(p[1]), z=0.05)
        marker("velocities", tid, Marker.ARROW, (1.0, 0.2, 0.0, 1.0), (0.03, 0.06, 0.06)).points = _points(
            Point, [p, p + v]
        )
        marker("forecasts", tid, Marker.LINE_LIST, (1.0, 0.5, 0.0, 0.4), (0.01, 0.01, 0.01)).points = _points(
            Point, forecast_segments(rings[i], scale)
        )
    plan = scene.plan
    if len(plan.via_points):
        marker("via_points", 0, Marker.SPHERE_LIST, (0.9, 0.0, 0.9, 1.0), (0.1, 0.1, 0.1)).points = _points(
            Point, plan.via_points
        )
    if len(plan.waypoints) >= 2:
        marker("plan", 0, Marker.LINE_STRIP, (0.0, 0.8, 0.2, 1.0), (0.04, 0.04, 0.04)).points = _points(
            Point, plan.waypoints
        )
    segments = [np.stack([c[:-1], c[1:]], axis=1).reshape(-1, 2) for c in plan.candidate_polylines if len(c) >= 2]
    if segments:
        marker("candidates", 0, Marker.LINE_LIST, (0.5, 0.5, 0.5, 0.3), (0.01, 0.01, 0.01)).points = _points(
            Point, np.concatenate(segments)
        )
    return out
