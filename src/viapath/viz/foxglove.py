"""Runs as Foxglove sees them: one MCAP per run, or a live WebSocket view, built from the scene.

Source: docs/design.md §9 (foxglove-sdk writes MCAP and serves a live WebSocket view with Foxglove's
schemas; the paper's Fig. 4 as a 3-D scene, time as the height). Every message is
built from a :class:`viapath.viz.scene.CycleScene`, the neutral description the ROS 2 node's
MarkerArray shares. Needs the ``viz`` extra (``foxglove-sdk``); imported only when asked for.

Topics (one message per planning cycle on each, log time = simulated time, from 0):

================================  ===========================  ========================================
topic                             schema                       content
================================  ===========================  ========================================
``/tf``                           foxglove.FrameTransforms     world → base → each scanner; world → xyt
``/robot/footprint``              foxglove.SceneUpdate         the robot's disc and heading (frame base)
``/scan/<scanner>``               foxglove.LaserScan           each scan in its scanner's frame (laser)
``/perception/blind_sectors``     foxglove.SceneUpdate         what no scanner sees (frame base; laser)
``/perception/detections``        foxglove.SceneUpdate         this cycle's detections (laser)
``/perception/tracks``            foxglove.SceneUpdate         tracks: disc, velocity arrow, k·σ ring
``/path``                         foxglove.SceneUpdate         designated path, corridor, current subgoal
``/plan/candidates``              foxglove.SceneUpdate         every candidate, coloured by E
``/plan/chosen``                  foxglove.SceneUpdate         the chosen polyline and its via points
``/plan/costs``                   viapath.PlanCosts (JSON)     E of chosen and runner-up, per term if known
``/xyt``                          foxglove.SceneUpdate         Fig. 4: cylinders and the plan in x-y-t
``/metrics``                      viapath.Metrics (JSON)       speed, turn rate, clearance, deviation, …
================================  ===========================  ========================================

What we chose:
* Frames: ``world`` (the scenario's), ``base`` (robot centre, x forward), ``laser_<name>`` per
  scanner (its mounting pose), ``xyt`` (identity under world; heights in it are time ×
  ``time_scale_m_per_s``). The x-y-t view is its own topic in its own frame so a 3-D panel shows
  it alone (the layout's right-hand panel) while the main panel looks down on the world.
* Each SceneUpdate first deletes everything its topic drew before, so a track that is gone
  disappears; static content (path, corridor) is still sent every cycle, so scrubbing to any time
  shows it and every topic has one message per cycle. What never changes in its frame (footprint,
  blind region: frame-locked to ``base``; the path for a given subgoal) is one message built once.
* Every protobuf message that changes per cycle (``/tf``, scans, every ``SceneUpdate``) is
  encoded by :mod:`viapath.viz.protobuf_wire` (a pose is one ``struct.pack``, a point list one
  numpy array) against Foxglove's own schemas, on channels that take bytes; what never changes
  (colours, the footprint, the blind region, the path for a subgoal) is built once with
  foxglove-sdk's message classes. ``tests/viz/test_wire_topics.py`` decodes every hand-encoded
  topic and compares it, field by field, with the message the SDK's classes build. MCAP chunks
  are LZ4-compressed (cheaper than zstd per cycle).
* Readings a driver marks invalid (inf, NaN, 0, below the minimum range) are sent as NaN, which
  Foxglove leaves out.
* JSON numbers that are not finite (no one in sight: clearance inf) are sent as ``null``.
* Live: the simulation is paced so that simulated time runs ``rate`` times as fast as the wall
  clock; a SIGINT ends the run, and the server is stopped in every case.
* An MCAP without the live view is built and written by a process of its own
  (:mod:`viapath.viz.mcap_process`), so the run is not slowed by the messages: same file.
"""

from __future__ import annotations

import json
import math
import os
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from viapath.viz import protobuf_wire as wire
from viapath.viz.mcap_process import cycle_input, scene_inputs, static_input
from viapath.viz.scene import CycleScene, ForecastSettings, SceneBuilder, _mesh_triangles, candidate_colour

TF = "/tf"
FOOTPRINT = "/robot/footprint"
BLIND = "/perception/blind_sectors"
DETECTIONS = "/perception/detections"
TRACKS = "/perception/tracks"
PATH = "/path"
STATIC = "/world/static"
CANDIDATES = "/plan/candidates"
CHOSEN = "/plan/chosen"
COSTS = "/plan/costs"
XYT = "/xyt"
METRICS = "/metrics"
WORLD, BASE, XYT_FRAME = "world", "base", "xyt"

COSTS_SCHEMA: dict[str, Any] = {
    "title": "viapath.PlanCosts",
    "type": "object",
    "properties": {
        "time_s": {"type": "number"},
        "status": {"type": "string"},
        "speed_mps": {"type": "number"},
        "candidate_count": {"type": "integer"},
        "terms_available": {"type": "boolean"},
        "chosen": {"type": ["object", "null"]},
        "runner_up": {"type": ["object", "null"]},
        "margin": {"type": ["number", "null"], "description": "E(runner-up) - E(chosen)"},
    },
}
METRICS_SCHEMA: dict[str, Any] = {
    "title": "viapath.Metrics",
    "type": "object",
    "properties": {
        name: {"type": ["number", "null"]}
        for name in (
            "time_s",
            "speed_mps",
            "turn_rate_radps",
            "command_speed_mps",
            "command_turn_rate_radps",
            "clearance_m",
            "lateral_deviation_m",
            "plan_time_ms",
            "shield_interventions",
            "tracks",
            "candidates",
        )
    },
}


# json.dumps(..., allow_nan=False) makes an encoder per call; one, made once, writes the same text.
_JSON = json.JSONEncoder(allow_nan=False)


class ViewError(ValueError):
    """A view cannot be set up (bad output path, missing extra, busy port)."""


def scan_topic(name: str) -> str:
    return f"/scan/{name}"


def scanner_frame(name: str) -> str:
    return f"laser_{name}"


def _foxglove():
    try:
        import foxglove
    except ImportError:
        raise ViewError("--mcap/--live need foxglove-sdk: pip install 'viapath[viz]'") from None
    return foxglove


# -- messages ------------------------------------------------------------------------------------


class FoxglovePublisher:
    """Logs one cycle's scene on a foxglove ``Context`` (whatever sinks it has: MCAP, WebSocket)."""

    def __init__(
        self, context, path, robot_radius_m: float, settings: ForecastSettings | None = None, xyt_segments: int = 16
    ):
        self.fg = _foxglove()
        from foxglove import messages

        self.m = messages
        self.context = context
        self.settings = settings
        self.builder: SceneBuilder = None  # type: ignore[assignment]  # made by start(), at the first cycle
        self.path = path
        self.robot_radius_m = robot_radius_m
        self.xyt_segments = int(xyt_segments)
        self.channels: dict[str, Any] = {}
        self.cycles = 0
        self._setup_constants()

    # channels are made at the first cycle, when the scanners are known
    def _open_channels(self, scene: CycleScene) -> None:
        from foxglove import Channel, Schema

        ctx = self.context
        # Every FrameTransforms, SceneUpdate and LaserScan is encoded here (viapath.viz.protobuf_wire)
        # against Foxglove's own schema, so these channels take bytes.
        self.channels[TF] = Channel(
            TF, message_encoding="protobuf", schema=self.m.FrameTransforms.get_schema(), context=ctx
        )
        topics = [FOOTPRINT, TRACKS, PATH, STATIC, CANDIDATES, CHOSEN, XYT]
        if scene.scanners:
            topics[1:1] = [BLIND, DETECTIONS]
        scene_schema = self.m.SceneUpdate.get_schema()
        for topic in topics:
            self.channels[topic] = Channel(topic, message_encoding="protobuf", schema=scene_schema, context=ctx)
        scan_schema = self.m.LaserScan.get_schema()
        for scanner in scene.scanners:
            topic = scan_topic(scanner.name)
            self.channels[topic] = Channel(topic, message_encoding="protobuf", schema=scan_schema, context=ctx)
        for topic, schema in ((COSTS, COSTS_SCHEMA), (METRICS, METRICS_SCHEMA)):
            self.channels[topic] = Channel(
                topic,
                message_encoding="json",
                context=ctx,
                schema=Schema(name=schema["title"], encoding="jsonschema", data=json.dumps(schema).encode()),
            )

    def __call__(self, record) -> CycleScene:
        """The ``on_step`` callback of :func:`viapath.sim.loop.run_episode`."""
        scene = self.scene_of(record)
        self.publish(scene)
        return scene

    def scene_of(self, record) -> CycleScene:
        if self.builder is None:
            self.start(static_input(record))
        return self.build(cycle_input(record))

    def start(self, static: tuple) -> None:
        """Take what stays the same for the run (:func:`viapath.viz.mcap_process.static_input`: the
        planner's forecast settings unless given, the scanners) before the first cycle."""
        self.run_static = static
        self.builder = SceneBuilder(self.path, self.robot_radius_m, self.settings or static[0])

    def build(self, inputs: tuple) -> CycleScene:
        """The scene of one cycle from :func:`viapath.viz.mcap_process.cycle_input` (the writer process
        receives the same tuple)."""
        *cycle, truth, parts = scene_inputs(inputs, self.run_static)
        return self.builder.build(*cycle, true_people=truth, perception_parts=parts)  # type: ignore[misc]

    def open_channels(self, scene: CycleScene) -> None:
        if not self.channels:
            self._open_channels(scene)

    def publish(self, scene: CycleScene) -> None:
        self.open_channels(scene)
        ns = int(round(scene.time_s * 1e9))
        ch = self.channels
        ch[TF].log(self._transforms(scene, ns), log_time=ns)
        ch[FOOTPRINT].log(self._footprint(scene), log_time=ns)
        for scanner in scene.scanners:
            ch[scan_topic(scanner.name)].log(self._scan(scanner, ns), log_time=ns)
        if scene.scanners:
            ch[BLIND].log(self._blind(scene), log_time=ns)
            ch[DETECTIONS].log(self._detections(scene, ns), log_time=ns)
        ch[TRACKS].log(self._tracks(scene, ns), log_time=ns)
        ch[PATH].log(self._path(scene), log_time=ns)
        ch[STATIC].log(self._static(scene), log_time=ns)
        ch[CANDIDATES].log(self._candidates(scene, ns), log_time=ns)
        ch[CHOSEN].log(self._chosen(scene, ns), log_time=ns)
        ch[COSTS].log(_JSON.encode(costs_message(scene)).encode(), log_time=ns)
        ch[XYT].log(self._xyt(scene, ns), log_time=ns)
        ch[METRICS].log(_JSON.encode(metrics_message(scene)).encode(), log_time=ns)
        self.cycles += 1

    # -- pieces --------------------------------------------------------------------------------
    # Built for speed (writing must cost little beside the run). What is the same all run
    # (colours, poses, the footprint, the blind region, the path for a given subgoal) is encoded
    # once, with foxglove-sdk's classes; what changes every cycle is encoded by
    # viapath.viz.protobuf_wire (one struct.pack per pose, numpy for point lists); a track that did
    # not change since the last cycle reuses its encoding; the x-y-t people are one numpy record
    # each (every person's entity has the same layout but for its id).
    def _setup_constants(self) -> None:
        m = self.m
        C = lambda r, g, b, a=1.0: m.Color(r=r, g=g, b=b, a=a)
        self.colours = {
            "robot": C(0.1, 0.3, 0.9),
            "robot_fill": C(0.1, 0.3, 0.9, 0.35),
            "blind": C(0.3, 0.3, 0.3, 0.8),
            "grey": C(0.4, 0.4, 0.4),
            "detection": C(1.0, 0.55, 0.0, 0.7),
            "track": C(0.85, 0.15, 0.15, 0.6),
            "track_sigma": C(0.85, 0.15, 0.15, 0.2),
            "track_text": C(0.5, 0.0, 0.0),
            "arrow": C(0.6, 0.0, 0.0),
            "path": C(0.2, 0.2, 0.2),
            "corridor": C(0.2, 0.6, 0.2, 0.7),
            "subgoal": C(0.9, 0.7, 0.0),
            "subgoal_text": C(0.5, 0.4, 0.0),
            "chosen": C(0.0, 0.45, 1.0),
            "chosen_text": C(0.0, 0.2, 0.6),
            "via": C(0.0, 0.0, 0.0),
            "mesh": C(0.9, 0.2, 0.2, 0.35),
            "ring": C(0.7, 0.1, 0.1, 0.9),
            "axis": C(0.5, 0.0, 0.0),
            "time_axis": C(0.4, 0.4, 0.4, 0.6),
            "static": C(0.1, 0.1, 0.1, 0.9),
        }
        self.identity = self._pose()
        self.delete_all = m.SceneEntityDeletion(type=m.SceneEntityDeletionType.All)
        self.wire = {
            "identity": self.identity.encode(),
            "delete_all": self.delete_all.encode(),
            **{name: colour.encode() for name, colour in self.colours.items()},
        }
        self.wire["deletions"] = wire.message_field(1, self.wire["delete_all"])  # a SceneUpdate's "delete all"
        self.wire["via_size"] = wire.vector3(0.1, 0.1, 0.1)
        for name in ("track", "track_sigma"):  # a CylinderPrimitive's colour is its field 5
            self.wire[f"{name}_field"] = wire.message_field(5, self.wire[name])
        self.static: dict[Any, Any] = {}
        self.candidate_colours: dict[int, bytes] = {}
        self.track_cache: dict[tuple, bytes] = {}  # the last cycle's tracks: key -> entity without timestamp
        self.person_names: dict[int, bytes] = {}  # track id -> the encoded id of its x-y-t entity

    def _points(self, xy: np.ndarray, z: float = 0.0) -> list:
        P = self.m.Point3
        return [P(x=a, y=b, z=z) for a, b in np.asarray(xy, dtype=float).reshape(-1, 2).tolist()]

    def _pose(self, x=0.0, y=0.0, z=0.0, yaw=0.0):
        m = self.m
        return m.Pose(
            position=m.Vector3(x=float(x), y=float(y), z=float(z)),
            orientation=m.Quaternion(x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2)),
        )

    def _line(self, points: list, colour, thickness=0.03, loop=False):
        m = self.m
        kind = m.LinePrimitiveLineType.LineLoop if loop else m.LinePrimitiveLineType.LineStrip
        return m.LinePrimitive(type=kind, pose=self.identity, thickness=thickness, points=points, color=colour)

    def _disc(self, x, y, radius, colour, z=0.0, height=0.01):
        m = self.m
        return m.CylinderPrimitive(
            pose=self._pose(x, y, z + 0.5 * height), size=m.Vector3(x=2 * radius, y=2 * radius, z=height), color=colour
        )

    def _text(self, x, y, z, text, colour, size=12.0):
        return self.m.TextPrimitive(
            pose=self._pose(x, y, z), billboard=True, font_size=size, scale_invariant=True, color=colour, text=text
        )

    def _update(self, stamp, frame, id_, primitives: dict, frame_locked: bool = False) -> bytes:
        """An encoded SceneUpdate built with the SDK's classes (for what is encoded once)."""
        m = self.m
        entity = m.SceneEntity(timestamp=stamp, frame_id=frame, id=id_, frame_locked=frame_locked, **primitives)
        return m.SceneUpdate(deletions=[self.delete_all], entities=[entity]).encode()

    @staticmethod
    def _wire_disc(x, y, radius, colour: bytes, z=0.0, height=0.01) -> bytes:
        """:meth:`_disc`, encoded."""
        return wire.cylinder(wire.pose(x, y, z + 0.5 * height), 2 * radius, 2 * radius, height, colour)

    @staticmethod
    def _wire_text(x, y, z, text, colour: bytes, size=12.0) -> bytes:
        """:meth:`_text`, encoded."""
        return wire.text(wire.pose(x, y, z), text, size, colour)

    def _scene_update(self, entities: list[bytes]) -> bytes:
        """A SceneUpdate that first deletes what its topic drew before."""
        return self.wire["deletions"] + b"".join(wire.message_field(2, entity) for entity in entities)

    def _transforms(self, scene: CycleScene, ns: int) -> bytes:
        """world → base at the robot's pose, world → xyt, base → each scanner at its mount."""
        stamp = wire.stamp_field(ns)
        key = ("tf", *(s.name for s in scene.scanners))
        fixed = self.static.get(key)
        if fixed is None:  # what follows the timestamp of the transforms that never move
            fixed = self.static[key] = [wire.frame_transform_tail(WORLD, XYT_FRAME, 0.0, 0.0, 0.0)] + [
                wire.frame_transform_tail(BASE, scanner_frame(s.name), *s.mount_pose.tolist()) for s in scene.scanners
            ]
        x, y, heading = scene.robot_pose.tolist()
        return wire.frame_transforms(
            [stamp + wire.frame_transform_tail(WORLD, BASE, x, y, heading)] + [stamp + tail for tail in fixed]
        )

    def _footprint(self, scene: CycleScene) -> bytes:
        """The robot's disc and heading in the base frame: the same every cycle (frame-locked)."""
        if "footprint" not in self.static:
            m, c, r = self.m, self.colours, scene.robot_radius_m
            self.static["footprint"] = self._update(
                None,
                BASE,
                "robot",
                {
                    "lines": [self._line(self._points(scene.footprint()), c["robot"], 0.03)],
                    "cylinders": [self._disc(0.0, 0.0, r, c["robot_fill"])],
                    "arrows": [
                        m.ArrowPrimitive(
                            pose=self._pose(z=0.02),
                            shaft_length=0.8 * r,
                            shaft_diameter=0.03,
                            head_length=0.12,
                            head_diameter=0.08,
                            color=c["robot"],
                        )
                    ],
                },
                frame_locked=True,
            )
        return self.static["footprint"]

    def _scan(self, scanner, ns: int) -> bytes:
        ranges = np.asarray(scanner.ranges_m, dtype=float)
        valid = np.isfinite(ranges) & (ranges >= max(scanner.range_min_m, 1e-9)) & (ranges <= scanner.range_max_m)
        ranges = np.where(valid, ranges, np.nan)
        return wire.laser_scan(
            ns, scanner_frame(scanner.name), self.wire["identity"], scanner.angle_min_rad, scanner.angle_max_rad, ranges
        )

    def _blind(self, scene: CycleScene) -> bytes:
        """What no scanner sees, in the base frame: fixed by the mounts, so one cached message."""
        if "blind" not in self.static:
            c = self.colours
            primitives: dict[str, list] = {}
            if len(scene.blind_polygon_world):
                # The polygon is given in the world at the robot's pose: bring it into the robot frame.
                x, y, heading = scene.robot_pose
                cos, sin = math.cos(-heading), math.sin(-heading)
                rel = scene.blind_polygon_world - [x, y]
                local = np.column_stack([cos * rel[:, 0] - sin * rel[:, 1], sin * rel[:, 0] + cos * rel[:, 1]])
                primitives["lines"] = [self._line(self._points(local, 0.01), c["blind"], 0.015, loop=True)]
                primitives["texts"] = [
                    self._text(
                        0.35 * math.cos(0.5 * (a + b)), 0.35 * math.sin(0.5 * (a + b)), 0.05, "blind", c["grey"], 11.0
                    )
                    for a, b in scene.blind_sectors_rad
                ]
            self.static["blind"] = self._update(None, BASE, "blind", primitives, frame_locked=True)
        return self.static["blind"]

    def _detections(self, scene: CycleScene, ns: int) -> bytes:
        colour = self.wire["detection"]
        discs = [
            self._wire_disc(cx, cy, r, colour, height=0.02)
            for (cx, cy), r in zip(scene.detections_world.tolist(), scene.detection_radii_m.tolist())
        ]
        return self._scene_update(
            [wire.entity_head(ns, WORLD, "detections") + wire.primitives(wire.ENTITY_CYLINDERS, discs)]
        )

    def _tracks(self, scene: CycleScene, ns: int) -> bytes:
        w = self.wire
        tracks = scene.tracks
        k = self.builder.settings.uncertainty_sigmas if self.builder else 2.0
        stamp = wire.stamp_field(ns)
        track_colour, sigma_colour = w["track_field"], w["track_sigma_field"]
        cylinders, texts, arrows = (
            wire.tag(field, 2) for field in (wire.ENTITY_CYLINDERS, wire.ENTITY_TEXTS, wire.ENTITY_ARROWS)
        )
        cache, self.track_cache = self.track_cache, {}
        entities = []
        for key in zip(
            tracks.positions[:, 0].tolist(),
            tracks.positions[:, 1].tolist(),
            tracks.velocities[:, 0].tolist(),
            tracks.velocities[:, 1].tolist(),
            tracks.radii_m.tolist(),
            tracks.position_sigma_m.tolist(),
            tracks.velocity_sigma_mps.tolist(),
            tracks.ids.tolist(),
        ):
            body = cache.get(key)
            if body is None:
                px, py, vx, vy, r, sp, sv, track = key
                speed = math.hypot(vx, vy)
                # The disc and the k·σ ring as _disc draws them (centre at half the height).
                disc = wire.upright_cylinder(px, py, 0.0 + 0.5 * 0.1, 2 * r, 2 * r, 0.1, track_colour)
                ring = wire.upright_cylinder(
                    px, py, 0.0 + 0.5 * 0.005, 2 * (r + k * sp), 2 * (r + k * sp), 0.005, sigma_colour
                )
                label = self._wire_text(px, py, 0.3, f"{track}: {speed:.2f} m/s ±{sv:.2f}", w["track_text"])
                body = (
                    wire.string_field(2, WORLD)
                    + wire.string_field(3, f"track-{track}")
                    + cylinders
                    + wire.varint(len(disc))
                    + disc
                    + cylinders
                    + wire.varint(len(ring))
                    + ring
                    + texts
                    + wire.varint(len(label))
                    + label
                )
                if speed > 1e-6:
                    arrow = wire.arrow(wire.pose(px, py, 0.12, math.atan2(vy, vx)), speed, 0.03, 0.1, 0.08, w["arrow"])
                    body += arrows + wire.varint(len(arrow)) + arrow
            self.track_cache[key] = body
            entities.append(stamp + body)
        return self._scene_update(entities)

    def _path(self, scene: CycleScene) -> bytes:
        """Path, corridor and the current subgoal: one cached message per subgoal."""
        key = ("path", scene.subgoal_index, *(round(value, 9) for value in scene.subgoal.tolist()))
        if key not in self.static:
            c, view = self.colours, self.builder.path_view
            lines = [self._line(self._points(view.waypoints), c["path"], 0.02)]
            lines += [self._line(self._points(outline), c["corridor"], 0.015) for outline in view.corridor_outlines]
            sx, sy = scene.subgoal.tolist()
            m = self.m
            self.static[key] = self._update(
                None,
                WORLD,
                "path",
                {
                    "lines": lines,
                    "spheres": [
                        m.SpherePrimitive(
                            pose=self._pose(sx, sy, 0.05), size=m.Vector3(x=0.15, y=0.15, z=0.15), color=c["subgoal"]
                        )
                    ],
                    "texts": [self._text(sx, sy, 0.25, f"subgoal {scene.subgoal_index}", c["subgoal_text"])],
                },
            )
        return self.static[key]

    def _static(self, scene: CycleScene) -> bytes:
        """The static layer the planner was told about, as one line list (a known map: the same message
        every cycle, encoded once)."""
        segments = scene.static_segments
        key = ("static", segments.tobytes())
        cached = self.static.get("static_last")
        if cached is not None and cached[0] == key:
            return cached[1]
        m = self.m
        if len(segments):
            line = m.LinePrimitive(
                type=m.LinePrimitiveLineType.LineList,
                pose=self.identity,
                thickness=0.03,
                points=self._points(segments.reshape(-1, 2), 0.02),
                color=self.colours["static"],
            )
            message = self._update(None, WORLD, "static", {"lines": [line]})
        else:
            message = self.wire["deletions"]
        self.static["static_last"] = (key, message)
        return message

    def _candidates(self, scene: CycleScene, ns: int) -> bytes:
        plan = scene.plan
        costs = plan.candidate_costs
        lines = []
        polylines = plan.candidate_polylines
        if polylines:
            finite = costs[np.isfinite(costs)] if len(costs) else costs
            low, high = (float(finite.min()), float(finite.max())) if len(finite) else (0.0, 0.0)
            # Colours in 16 steps of E (-1: no finite cost), each encoded once.
            padded = np.full(len(polylines), np.inf)
            padded[: min(len(costs), len(polylines))] = costs[: len(polylines)]
            with np.errstate(invalid="ignore"):
                steps = np.rint(15 * ((padded - low) / (high - low))) if high > low else np.zeros(len(padded))
            steps = np.where(np.isfinite(padded), steps, -1).astype(int).tolist()
            counts = [len(line) for line in polylines]
            xyz = np.empty((sum(counts), 3))
            xyz[:, :2], xyz[:, 2] = np.concatenate(polylines), 0.01
            points = wire.points_field(5, xyz)
            head = self.static.get("candidate_head")
            if head is None:
                head = self.static["candidate_head"] = (
                    wire.varint_field(1, wire.LINE_STRIP)
                    + wire.message_field(2, self.wire["identity"])
                    + wire.double_field(3, 0.01)
                )
            start = 0
            for u, count in zip(steps, counts):
                colour = self.candidate_colours.get(u)
                if colour is None:
                    # Step u of 16 is the colour of E at u/15 of the way from the lowest to the highest.
                    rgba = candidate_colour(u / 15 if u >= 0 else math.inf, 0.0, 1.0)
                    colour = self.candidate_colours[u] = wire.message_field(
                        6, self.m.Color(r=rgba[0], g=rgba[1], b=rgba[2], a=rgba[3]).encode()
                    )
                end = start + 29 * count
                lines.append(head + points[start:end] + colour)
                start = end
        entity = wire.scene_entity(ns, WORLD, "candidates", lines=lines)
        return self._scene_update([entity])

    def _chosen(self, scene: CycleScene, ns: int) -> bytes:
        w = self.wire
        plan = scene.plan
        line = plan.waypoints if len(plan.waypoints) else np.array([scene.robot_pose[:2], plan.target])
        xyz = np.empty((len(line), 3))
        xyz[:, :2], xyz[:, 2] = line, 0.02
        spheres = [wire.sphere(wire.pose(x, y, 0.03), w["via_size"], w["via"]) for x, y in plan.via_points.tolist()]
        tx, ty = plan.target.tolist()
        return self._scene_update(
            [
                wire.entity_head(ns, WORLD, "chosen")
                + wire.message_field(wire.ENTITY_LINES, wire.line_primitive(xyz, w["chosen"], w["identity"], 0.04))
                + wire.primitives(wire.ENTITY_SPHERES, spheres)
                + wire.message_field(
                    wire.ENTITY_TEXTS,
                    self._wire_text(tx, ty, 0.3, f"{plan.status} {plan.speed_mps:.2f} m/s", w["chosen_text"]),
                )
            ]
        )

    def _xyt_layout(self, segments: int) -> tuple[np.dtype, np.ndarray]:
        """One person's x-y-t entity after its id, as a numpy record: constant bytes (tags, lengths,
        pose, colours, the mesh's triangles) and the points of its three rings, its axis and its
        mesh; with the template filling the constant bytes."""
        key = ("xyt-layout", segments)
        if key in self.static:
            return self.static[key]
        w = self.wire
        fields: list[tuple[Any, ...]] = []
        template: list[bytes] = []

        def const(data: bytes) -> None:
            fields.append((f"c{len(fields)}", f"V{len(data)}"))
            template.append(data)

        def points(name: str, field: int, count: int) -> None:
            fields.append((name, wire.POINT_DTYPE, (count,)))
            template.append(wire.points_field(field, np.zeros((count, 3))))

        def line(name: str, kind: int, count: int, colour: bytes) -> None:
            head = wire.varint_field(1, kind) + wire.message_field(2, w["identity"]) + wire.double_field(3, 0.01)
            tail = wire.message_field(6, colour)
            const(wire.tag(wire.ENTITY_LINES, 2) + wire.varint(len(head) + 29 * count + len(tail)) + head)
            points(name, 5, count)
            const(tail)

        for r in range(3):
            line(f"ring{r}", wire.LINE_LOOP, segments, w["ring"])
        line("axis", wire.LINE_STRIP, 2, w["axis"])
        vertices = 3 * segments + 2
        head = wire.message_field(1, w["identity"])
        tail = wire.message_field(3, w["mesh"]) + wire.fixed32_packed_field(5, wire_triangles(segments))
        const(wire.tag(wire.ENTITY_TRIANGLES, 2) + wire.varint(len(head) + 29 * vertices + len(tail)) + head)
        points("mesh", 2, vertices)
        const(tail)
        dtype = np.dtype(fields)
        row = np.frombuffer(b"".join(template), dtype=np.uint8)
        assert len(row) == dtype.itemsize
        self.static[key] = (dtype, row)
        return self.static[key]

    def _xyt(self, scene: CycleScene, ns: int) -> bytes:
        w = self.wire
        xyt = scene.xyt
        scale = xyt.settings.time_scale_m_per_s
        stretch = np.array([1.0, 1.0, scale])
        segments = self.xyt_segments
        identity = w["identity"]
        head = wire.stamp_field(ns) + wire.string_field(2, XYT_FRAME)
        entities = []
        if xyt.persons:
            # All people at once: three rings each (0, cone cap or mid-horizon, horizon), the caps'
            # centres on the axis; each person's entity a numpy record of the same layout (see _xyt_layout).
            rings, centres = xyt.all_rings_and_centres(segments)
            rings = rings * stretch  # (P, 3, S, 3)
            count = len(rings)
            caps = axes = centres[:, ::2] * stretch  # (P, 2, 3): the axis from t = 0 to the horizon
            dtype, template = self._xyt_layout(segments)
            size = dtype.itemsize
            records = np.empty((count, size), dtype=np.uint8)
            records[:] = template

            def put(field: str, first: int, xyz: np.ndarray, strides: tuple = ()) -> None:
                # The x, y, z of each point record (tag, length, then a tag before each double: 29
                # bytes) as one strided view of unaligned doubles, written in one assignment.
                offset = dtype.fields[field][1] + 29 * first + 3  # type: ignore[index]  # a structured dtype
                np.ndarray(xyz.shape, dtype="<f8", buffer=records, offset=offset, strides=(size, *strides, 29, 9))[
                    ...
                ] = xyz

            # The three rings' lines have the same layout one after the other: one view for all.
            put("ring0", 0, rings, (dtype.fields["ring1"][1] - dtype.fields["ring0"][1],))  # type: ignore[index]
            put("axis", 0, axes)
            put("mesh", 0, rings.reshape(count, 3 * segments, 3))
            put("mesh", 3 * segments, caps)
            data, names = records.tobytes(), self.person_names
            for i, person in enumerate(xyt.persons):
                name = names.get(person.id)
                if name is None:
                    name = names[person.id] = wire.string_field(3, f"person-{person.id}")
                entities.append(head + name + data[i * size : (i + 1) * size])
        x, y = scene.robot_pose[:2].tolist()
        horizon = xyt.settings.horizon_s
        ticks = [
            self._wire_text(x - 0.3, y, t * scale, f"{t:g} s", w["grey"], 11.0) for t in (0.0, 0.5 * horizon, horizon)
        ]
        spheres = [
            wire.sphere(wire.pose(px, py, pt * scale), w["via_size"], w["via"])
            for px, py, pt in xyt.via_points_xyt.tolist()
        ]
        entities.append(
            wire.entity_head(ns, XYT_FRAME, "robot-plan")
            + wire.primitives(
                wire.ENTITY_LINES,
                [
                    wire.line_primitive(xyt.plan_xyt * stretch, w["chosen"], identity, 0.04),
                    wire.line_primitive(
                        np.array([[x, y, 0.0], [x, y, horizon * scale]]), w["time_axis"], identity, 0.01
                    ),
                ],
            )
            + wire.primitives(wire.ENTITY_SPHERES, spheres)
            + wire.primitives(wire.ENTITY_TEXTS, ticks)
            + wire.message_field(wire.ENTITY_CYLINDERS, self._wire_disc(x, y, scene.robot_radius_m, w["robot_fill"]))
        )
        return self._scene_update(entities)


def wire_triangles(segments: int) -> np.ndarray:
    """Vertex indices of a three-ring cylinder with both caps (as :meth:`XYTScene.mesh_indexed`)."""
    return _mesh_triangles(3, segments)


def _finite(value) -> float | None:
    if value is None:
        return None
    value = float(value)
    return value if math.isfinite(value) else None


def metrics_message(scene: CycleScene) -> dict:
    return {"time_s": scene.time_s, **{name: _finite(value) for name, value in scene.series.items()}}


def costs_message(scene: CycleScene) -> dict:
    """E of the chosen and the runner-up candidate, with the per-term breakdown when the planner gives one."""
    plan = scene.plan
    terms = plan.cost_terms or {}

    def one(index: Any, cost: Any, key: str) -> dict[str, Any] | None:
        if index is None:
            return None
        entry: dict[str, Any] = {"index": int(index), "E": _finite(cost)}
        if isinstance(terms.get(key), dict):
            entry["terms"] = {str(k): _finite(v) for k, v in terms[key].items()}
        return entry

    chosen, runner = plan.chosen_cost, plan.runner_up_cost
    return {
        "time_s": scene.time_s,
        "status": plan.status,
        "speed_mps": _finite(plan.speed_mps),
        "candidate_count": int(len(plan.candidate_costs)),
        "terms_available": plan.cost_terms is not None,
        "chosen": one(plan.chosen, chosen, "chosen"),
        "runner_up": one(plan.runner_up, runner, "runner_up"),
        "margin": None if chosen is None or runner is None else runner - chosen,
    }


# -- running with a view ---------------------------------------------------------------------------


def display_overrides(scenario, planner_name: str) -> dict[str, Any]:
    """Planner options that make it keep every candidate for display (the viapath planner's
    ``record_candidates``), or nothing for planners without such an option."""
    from viapath.planning import planner_options

    return {"record_candidates": True} if "record_candidates" in planner_options(planner_name) else {}


def check_mcap_path(file: Path | str, force: bool = False, option: str = "--mcap") -> Path:
    """A file we may write: ends in .mcap, its folder exists and is writable, not there unless ``force``.
    Checked by creating the file, so the answer is true for the user running it (root included)."""
    file = Path(file)
    if file.suffix.lower() != ".mcap":
        raise ViewError(f"{option} {file}: expected a file ending in .mcap")
    if file.is_dir():
        raise ViewError(f"{option} {file}: is a folder; give a file name ending in .mcap")
    if not file.parent.is_dir():
        raise ViewError(f"{option} {file}: folder {file.parent} does not exist")
    if file.exists() and not force:
        raise ViewError(f"{option} {file}: file exists; add --force to overwrite it")
    existed = file.exists()
    try:
        with open(file, "ab"):
            pass
    except OSError as error:
        raise ViewError(f"{option} {file}: cannot write there ({error.strerror or error})") from None
    if not existed:
        file.unlink()
    return file


def check_output_folder(folder: Path | str, option: str = "--mcap-failures") -> Path:
    """A folder we may write files into (made if missing, its parent must exist)."""
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise ViewError(f"{option} {folder}: is a file, expected a folder")
    if not folder.exists():
        if not folder.parent.is_dir():
            raise ViewError(f"{option} {folder}: folder {folder.parent} does not exist")
        try:
            folder.mkdir()
        except OSError as error:
            raise ViewError(f"{option} {folder}: cannot create it ({error.strerror or error})") from None
    probe = folder / f".viapath-write-test-{os.getpid()}"
    try:
        probe.write_bytes(b"")
        probe.unlink()
    except OSError as error:
        raise ViewError(f"{option} {folder}: cannot write there ({error.strerror or error})") from None
    return folder


class Views:
    """The views of one run: an MCAP file, a live server, or both. Use as a context manager around
    ``run_episode(..., planner_overrides=views.planner_overrides, on_step=views.on_step)``.
    An MCAP alone is written by a process of its own (:mod:`viapath.viz.mcap_process`) unless
    ``in_process``; with ``live`` everything is logged in the run's process, which the view paces."""

    def __init__(
        self,
        scenario,
        planner_name: str,
        mcap: Path | str | None = None,
        force: bool = False,
        live: bool = False,
        rate: float = 1.0,
        host: str = "127.0.0.1",
        port: int = 8765,
        settings: ForecastSettings | None = None,
        announce: Callable[[str], None] | None = None,
        in_process: bool = False,
    ):
        if not (math.isfinite(rate) and rate > 0):
            raise ViewError(f"--rate: expected a number > 0, found {rate}")
        self.mcap = check_mcap_path(mcap, force) if mcap is not None else None
        self.force = force
        self.live, self.rate, self.host, self.port = live, float(rate), host, int(port)
        self.scenario, self.planner_name = scenario, planner_name
        self.settings = settings
        self.announce = announce or (lambda message: None)
        self.on_step: Callable | None = None
        self.planner_overrides: dict[str, Any] | None = None
        self.server: Any = None
        self.writer: Any = None
        self.writer_process: Any = None  # viapath.viz.mcap_process.MCAPWriterProcess (an MCAP without --live)
        self.in_process = in_process
        self.publisher: FoxglovePublisher = None  # type: ignore[assignment]  # made on entering, before any cycle
        self._clock_start: float | None = None
        if self.mcap is not None or live:
            _foxglove()
        if live and self.port != 0:
            _check_port_free(host, self.port)

    @property
    def active(self) -> bool:
        return self.mcap is not None or self.live

    def __enter__(self) -> Views:
        if not self.active:
            return self
        import foxglove

        from viapath.scenarios.build import scenario_path

        path = scenario_path(self.scenario)
        self.planner_overrides = display_overrides(self.scenario, self.planner_name)
        if not self.live and not self.in_process:
            from viapath.viz.mcap_process import MCAPWriterProcess

            self.writer_process = MCAPWriterProcess(
                self.mcap,  # type: ignore[arg-type]  # active and not live: an MCAP file
                self.force,
                path,
                self.scenario.robot.radius,
                FoxglovePublisher,
                ViewError,
                self.settings,
            )
            self.on_step = self.writer_process
            return self
        context = foxglove.Context()
        try:
            if self.mcap is not None:
                from foxglove.mcap import MCAPCompression, MCAPWriteOptions

                options = MCAPWriteOptions(compression=MCAPCompression.Lz4)
                self.writer = foxglove.open_mcap(
                    self.mcap, allow_overwrite=self.force, context=context, writer_options=options
                )
        except BaseException:
            self._close()
            raise
        self.context = context
        self.publisher = FoxglovePublisher(context, path, self.scenario.robot.radius, self.settings)
        self.on_step = self._paced if self.live else self.publisher
        return self

    def _start_server(self) -> None:
        import foxglove
        from foxglove.websocket import Capability

        try:
            self.server = foxglove.start_server(
                name=f"viapath {self.scenario.name}",
                host=self.host,
                port=self.port,
                context=self.context,
                capabilities=[Capability.Time],
            )
        except Exception as error:  # the SDK raises its own error type for a busy port
            raise ViewError(f"--live: cannot serve on {self.host}:{self.port} ({error})") from None
        self.announce(f"live view: ws://{self.host}:{self.server.port} (Foxglove: Open connection, Foxglove WebSocket)")

    def _paced(self, record) -> None:
        """Publish, then hold the simulation so that it runs ``rate`` times as fast as the wall clock.
        The server starts at the first cycle, once every channel exists, so a client that connects
        is told of all of them at once."""
        scene = self.publisher.scene_of(record)
        if self.server is None:
            self.publisher.open_channels(scene)
            self._start_server()
        now = time.perf_counter()
        if self._clock_start is None:
            self._clock_start = now - record.time_s / self.rate
        self.publisher.publish(scene)
        self.server.broadcast_time(int(round(record.time_s * 1e9)))
        wait = self._clock_start + (record.time_s + self.scenario.dt_s) / self.rate - time.perf_counter()
        if wait > 0:
            time.sleep(wait)

    def __exit__(self, *exc) -> None:
        self._close()

    def _close(self) -> None:
        if self.writer_process is not None:
            writer, self.writer_process = self.writer_process, None
            writer.close()
        if self.writer is not None:
            self.writer.close()
            self.writer = None
        if self.server is not None:
            self.server.stop()
            self.server = None


def _check_port_free(host: str, port: int) -> None:
    import socket

    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        try:
            probe.bind((host, port))
        except OSError as error:
            raise ViewError(
                f"--port {port}: {host}:{port} is in use ({error.strerror or error}); "
                "give another port, or 0 for any free one"
            ) from None


def record_episode(
    scenario, file: Path | str, planner: str | None = None, force: bool = False, in_process: bool = False, **run_kwargs
):
    """Run one episode and write its MCAP (by a writer process unless ``in_process``); returns the episode."""
    from viapath.sim.loop import run_episode

    name = planner or scenario.planner.name
    with Views(scenario, name, mcap=file, force=force, in_process=in_process) as views:
        return run_episode(
            scenario, planner=name, planner_overrides=views.planner_overrides, on_step=views.on_step, **run_kwargs
        )


# -- benchmark failures ----------------------------------------------------------------------------


def failure_reasons(row: dict) -> list[str]:
    """Why a benchmark row is a failure (empty: it is not). Rows with an error are not episodes."""
    if row.get("error"):
        return []
    reasons = []
    if row.get("collision"):
        reasons.append("collision")
    if row.get("at_fault_collision"):
        reasons.append("at_fault_collision")
    if (row.get("time_outside_corridor_s") or 0.0) > 0.0:
        reasons.append("outside_corridor")
    if row.get("reached_goal") is False:
        reasons.append("missed_goal")
    return reasons


def failure_file_name(scenario_name: str, planner: str, perception: str = "oracle", seed: int | None = None) -> str:
    safe = lambda text: "".join(c if c.isalnum() or c in "-_." else "_" for c in str(text))
    return f"{safe(scenario_name)}__{safe(planner)}__{safe(perception)}.mcap"


def write_failure_mcaps(
    rows: list[dict],
    scenarios: list[dict],
    folder: Path | str,
    force: bool = True,
    progress: Callable[[str], None] | None = None,
) -> list[dict]:
    """Re-run each failed episode of a benchmark (same scenario, planner, perception and seed: the
    runs are deterministic) and write its MCAP into ``folder``. Returns one entry per file with the
    reasons and whether the re-run failed the same way (it should; a mismatch is reported)."""
    from viapath.scenarios import scenario_from_dict

    folder = Path(folder)
    by_name = {s["name"]: s for s in scenarios}
    written = []
    for row in rows:
        reasons = failure_reasons(row)
        if not reasons or row["scenario"] not in by_name:
            continue
        file = folder / failure_file_name(row["scenario"], row["planner"], row["perception"])
        scenario = scenario_from_dict(by_name[row["scenario"]], row["scenario"])
        episode = record_episode(
            scenario, file, planner=row["planner"], force=force, perception=row["perception"], seed=int(row["seed"])
        )
        again = failure_reasons(
            {
                **row,
                **{
                    k: episode.metrics.get(k)
                    for k in ("collision", "at_fault_collision", "time_outside_corridor_s", "reached_goal")
                },
            }
        )
        entry = {
            "file": str(file),
            "scenario": row["scenario"],
            "planner": row["planner"],
            "reasons": reasons,
            "reproduced": again == reasons,
        }
        written.append(entry)
        if progress is not None:
            progress(
                f"{file.name}: {', '.join(reasons)}"
                + ("" if entry["reproduced"] else f" (re-run gave: {', '.join(again) or 'no failure'})")
            )
    return written


class _NoViews:
    """What :func:`open_views` returns when no view is asked for: changes nothing in the run."""

    planner_overrides = None
    on_step = None
    active = False

    def __enter__(self) -> _NoViews:
        return self

    def __exit__(self, *exc) -> None:
        return None


def open_views(
    scenario,
    planner_name: str,
    mcap: Path | str | None = None,
    force: bool = False,
    live: bool = False,
    rate: float = 1.0,
    port: int = 8765,
    announce: Callable[[str], None] | None = None,
):
    """The CLI's entry: checks every option (paths, rate, port, the extra) before the run starts."""
    if not live:
        if rate != 1.0:
            raise ViewError("--rate applies to --live only")
        if port != 8765:
            raise ViewError("--port applies to --live only")
    elif not 0 <= port <= 65535:
        raise ViewError(f"--port: expected 0..65535, found {port}")
    if force and mcap is None:
        raise ViewError("--force applies to --mcap only")
    if mcap is None and not live:
        return _NoViews()
    return Views(scenario, planner_name, mcap=mcap, force=force, live=live, rate=rate, port=port, announce=announce)


def check_failures_option(folder: Path | str) -> Path:
    """``viapath bench --mcap-failures DIR``: the extra is installed and DIR can take files."""
    _foxglove()
    return check_output_folder(folder)
