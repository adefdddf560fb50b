"""Every topic the publisher encodes itself (viapath.viz.protobuf_wire: transforms, scans and every
SceneUpdate built per cycle) decodes, with Foxglove's own schema, to the message foxglove-sdk's
classes build from the same scene, field by field.

The reference below is the publisher as it was written with the SDK's classes only (one
``foxglove.messages`` object per point, primitive and entity). Scenes come from real runs: the
paper's side case with laser perception (scans, detections, blind region, tracks with σ, moving
and still), the front case (candidates coloured by E, via points in x-y-t) and a crowd whose
people stand still (tracks reused from the previous cycle).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

messages = pytest.importorskip("foxglove.messages", reason="needs the viz extra (foxglove-sdk)")
pytest.importorskip("google.protobuf", reason="needs protobuf (viz extra)")

import foxglove  # noqa: E402
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory  # noqa: E402

from viapath.path import DesignatedPath  # noqa: E402
from viapath.scenarios import load_scenario, scenario_from_dict  # noqa: E402
from viapath.sim.loop import run_episode  # noqa: E402
from viapath.viz import foxglove as fx  # noqa: E402
from viapath.viz.scene import candidate_colour  # noqa: E402

m = messages


def _message_class(sdk_class, name: str):
    files = descriptor_pb2.FileDescriptorSet.FromString(sdk_class.get_schema().data)
    pool = descriptor_pool.DescriptorPool()
    for file in files.file:
        pool.Add(file)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(name))


SCENE_UPDATE = _message_class(m.SceneUpdate, "foxglove.SceneUpdate")
LASER_SCAN = _message_class(m.LaserScan, "foxglove.LaserScan")
FRAME_TRANSFORMS = _message_class(m.FrameTransforms, "foxglove.FrameTransforms")


# -- the reference: foxglove-sdk's classes only ------------------------------------------------------


def _pose(x=0.0, y=0.0, z=0.0, yaw=0.0):
    return m.Pose(
        position=m.Vector3(x=float(x), y=float(y), z=float(z)),
        orientation=m.Quaternion(x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2)),
    )


def _points(xyz) -> list:
    return [m.Point3(x=a, y=b, z=c) for a, b, c in np.asarray(xyz, dtype=float).reshape(-1, 3).tolist()]


def _line(xyz, colour, thickness, loop=False):
    kind = m.LinePrimitiveLineType.LineLoop if loop else m.LinePrimitiveLineType.LineStrip
    return m.LinePrimitive(type=kind, pose=_pose(), thickness=thickness, points=_points(xyz), color=colour)


def _disc(x, y, radius, colour, z=0.0, height=0.01):
    return m.CylinderPrimitive(
        pose=_pose(x, y, z + 0.5 * height), size=m.Vector3(x=2 * radius, y=2 * radius, z=height), color=colour
    )


def _text(x, y, z, text, colour, size=12.0):
    return m.TextPrimitive(
        pose=_pose(x, y, z), billboard=True, font_size=size, scale_invariant=True, color=colour, text=text
    )


def _stamp(ns):
    return m.Timestamp(ns // 1_000_000_000, ns % 1_000_000_000)


def _update(entities):
    return m.SceneUpdate(
        deletions=[m.SceneEntityDeletion(type=m.SceneEntityDeletionType.All)], entities=entities
    ).encode()


def reference(topic: str, scene, ns: int, colours: dict, k_sigma: float, segments: int, scanner=None):
    c, stamp = colours, _stamp(ns)
    if topic == fx.TF:

        def tf(parent, child, px, py, yaw):
            return m.FrameTransform(
                timestamp=stamp,
                parent_frame_id=parent,
                child_frame_id=child,
                translation=m.Vector3(x=float(px), y=float(py), z=0.0),
                rotation=m.Quaternion(x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2)),
            )

        x, y, heading = scene.robot_pose
        return m.FrameTransforms(
            transforms=[tf("world", "base", x, y, heading), tf("world", "xyt", 0.0, 0.0, 0.0)]
            + [tf("base", fx.scanner_frame(s.name), *s.mount_pose) for s in scene.scanners]
        ).encode()
    if topic == "scan":
        ranges = np.asarray(scanner.ranges_m, dtype=float)
        valid = np.isfinite(ranges) & (ranges >= max(scanner.range_min_m, 1e-9)) & (ranges <= scanner.range_max_m)
        return m.LaserScan(
            timestamp=stamp,
            frame_id=fx.scanner_frame(scanner.name),
            pose=_pose(),
            start_angle=scanner.angle_min_rad,
            end_angle=scanner.angle_max_rad,
            ranges=np.where(valid, ranges, np.nan).tolist(),
        ).encode()
    if topic == fx.DETECTIONS:
        discs = [
            _disc(x, y, r, c["detection"], height=0.02)
            for (x, y), r in zip(scene.detections_world.tolist(), scene.detection_radii_m.tolist())
        ]
        return _update([m.SceneEntity(timestamp=stamp, frame_id="world", id="detections", cylinders=discs)])
    if topic == fx.TRACKS:
        t, entities = scene.tracks, []
        for (px, py), (vx, vy), r, sp, sv, track in zip(
            t.positions.tolist(),
            t.velocities.tolist(),
            t.radii_m.tolist(),
            t.position_sigma_m.tolist(),
            t.velocity_sigma_mps.tolist(),
            t.ids.tolist(),
        ):
            speed = math.hypot(vx, vy)
            primitives = {
                "cylinders": [
                    _disc(px, py, r, c["track"], height=0.1),
                    _disc(px, py, r + k_sigma * sp, c["track_sigma"], height=0.005),
                ],
                "texts": [_text(px, py, 0.3, f"{track}: {speed:.2f} m/s ±{sv:.2f}", c["track_text"])],
            }
            if speed > 1e-6:
                primitives["arrows"] = [
                    m.ArrowPrimitive(
                        pose=_pose(px, py, 0.12, math.atan2(vy, vx)),
                        shaft_length=speed,
                        shaft_diameter=0.03,
                        head_length=0.1,
                        head_diameter=0.08,
                        color=c["arrow"],
                    )
                ]
            entities.append(m.SceneEntity(timestamp=stamp, frame_id="world", id=f"track-{track}", **primitives))
        return _update(entities)
    plan = scene.plan
    if topic == fx.CANDIDATES:
        costs, lines = plan.candidate_costs, []
        finite = costs[np.isfinite(costs)]
        low, high = (float(finite.min()), float(finite.max())) if len(finite) else (0.0, 0.0)
        for i, line in enumerate(plan.candidate_polylines):
            cost = float(costs[i]) if i < len(costs) else math.inf
            u = -1 if not math.isfinite(cost) else int(round(15 * (0 if high <= low else (cost - low) / (high - low))))
            r, g, b, a = candidate_colour(u / 15 if u >= 0 else math.inf, 0.0, 1.0)  # E in 16 steps
            xyz = np.column_stack([line, np.full(len(line), 0.01)])
            lines.append(_line(xyz, m.Color(r=r, g=g, b=b, a=a), 0.01))
        return _update([m.SceneEntity(timestamp=stamp, frame_id="world", id="candidates", lines=lines)])
    if topic == fx.CHOSEN:
        line = plan.waypoints if len(plan.waypoints) else np.array([scene.robot_pose[:2], plan.target])
        spheres = [
            m.SpherePrimitive(pose=_pose(x, y, 0.03), size=m.Vector3(x=0.1, y=0.1, z=0.1), color=c["via"])
            for x, y in plan.via_points.tolist()
        ]
        tx, ty = plan.target.tolist()
        return _update(
            [
                m.SceneEntity(
                    timestamp=stamp,
                    frame_id="world",
                    id="chosen",
                    lines=[_line(np.column_stack([line, np.full(len(line), 0.02)]), c["chosen"], 0.04)],
                    spheres=spheres,
                    texts=[_text(tx, ty, 0.3, f"{plan.status} {plan.speed_mps:.2f} m/s", c["chosen_text"])],
                )
            ]
        )
    assert topic == fx.XYT
    xyt = scene.xyt
    scale = xyt.settings.time_scale_m_per_s
    stretch = np.array([1.0, 1.0, scale])
    entities = []
    for i, person in enumerate(xyt.persons):
        rings = xyt.rings(i, segments)
        if len(rings) == 2:  # the publisher always draws three rings: add the mid-horizon one (same surface)
            rings = xyt.all_rings(segments)[i]
        rings = rings * stretch
        ends = np.array([0.0, xyt.settings.horizon_s])
        axis = np.column_stack([person.centre_at(ends), ends]) * stretch  # the caps' centres too
        vertices = np.concatenate([rings.reshape(-1, 3), axis])
        entities.append(
            m.SceneEntity(
                timestamp=stamp,
                frame_id="xyt",
                id=f"person-{person.id}",
                lines=[_line(ring, c["ring"], 0.01, loop=True) for ring in rings] + [_line(axis, c["axis"], 0.01)],
                triangles=[
                    m.TriangleListPrimitive(
                        pose=_pose(),
                        points=_points(vertices),
                        color=c["mesh"],
                        indices=fx.wire_triangles(segments).ravel().tolist(),
                    )
                ],
            )
        )
    x, y = scene.robot_pose[:2].tolist()
    horizon = xyt.settings.horizon_s
    entities.append(
        m.SceneEntity(
            timestamp=stamp,
            frame_id="xyt",
            id="robot-plan",
            lines=[
                _line(xyt.plan_xyt * stretch, c["chosen"], 0.04),
                _line([[x, y, 0.0], [x, y, horizon * scale]], c["time_axis"], 0.01),
            ],
            spheres=[
                m.SpherePrimitive(pose=_pose(px, py, pt * scale), size=m.Vector3(x=0.1, y=0.1, z=0.1), color=c["via"])
                for px, py, pt in xyt.via_points_xyt.tolist()
            ],
            texts=[_text(x - 0.3, y, t * scale, f"{t:g} s", c["grey"], 11.0) for t in (0.0, 0.5 * horizon, horizon)],
            cylinders=[_disc(x, y, scene.robot_radius_m, c["robot_fill"])],
        )
    )
    return _update(entities)


# -- the comparison ---------------------------------------------------------------------------------


def _ours(publisher, topic: str, scene, ns: int, scanner=None) -> bytes:
    return {
        "scan": lambda: publisher._scan(scanner, ns),
        fx.DETECTIONS: lambda: publisher._detections(scene, ns),
        fx.TRACKS: lambda: publisher._tracks(scene, ns),
        fx.CANDIDATES: lambda: publisher._candidates(scene, ns),
        fx.CHOSEN: lambda: publisher._chosen(scene, ns),
        fx.XYT: lambda: publisher._xyt(scene, ns),
    }[topic]()


def _compare_run(scenario, perception: str, every: int = 1) -> dict[str, int]:
    """Build every cycle's scene, encode each hand-encoded topic both ways and compare the decoded
    messages; returns how many primitives of each kind were compared."""
    path = DesignatedPath(scenario.path.waypoints, half_widths_m=scenario.path.widths())
    publisher = fx.FoxglovePublisher(foxglove.Context(), path, scenario.robot.radius)
    seen: dict[str, int] = {}

    def on_step(record):
        scene = publisher.scene_of(record)
        ns = int(round(scene.time_s * 1e9))
        k = publisher.builder.settings.uncertainty_sigmas
        # Tracks every cycle (the publisher reuses an unchanged track's encoding from the last one).
        topics = [fx.TRACKS] + ([fx.DETECTIONS, fx.CANDIDATES, fx.CHOSEN, fx.XYT] if record.step % every == 0 else [])
        for topic in topics:
            ours = SCENE_UPDATE.FromString(_ours(publisher, topic, scene, ns))
            theirs = SCENE_UPDATE.FromString(reference(topic, scene, ns, publisher.colours, k, publisher.xyt_segments))
            assert ours == theirs, (topic, record.step)
            for entity in ours.entities:
                for kind in ("arrows", "cylinders", "spheres", "lines", "triangles", "texts"):
                    seen[kind] = seen.get(kind, 0) + len(getattr(entity, kind))
        ours = FRAME_TRANSFORMS.FromString(publisher._transforms(scene, ns))
        assert ours == FRAME_TRANSFORMS.FromString(reference(fx.TF, scene, ns, publisher.colours, k, 0)), record.step
        seen["transforms"] = seen.get("transforms", 0) + len(ours.transforms)
        for scanner in scene.scanners if record.step % every == 0 else ():
            ours = LASER_SCAN.FromString(publisher._scan(scanner, ns))
            theirs = LASER_SCAN.FromString(reference("scan", scene, ns, publisher.colours, k, 0, scanner))
            np.testing.assert_array_equal(ours.ranges, theirs.ranges)  # NaN where invalid: compared apart
            del ours.ranges[:], theirs.ranges[:]
            assert ours == theirs
            seen["scans"] = seen.get("scans", 0) + 1

    run_episode(
        scenario,
        perception=perception,
        planner_overrides=fx.display_overrides(scenario, "viapath"),
        on_step=on_step,
        seed=1,
    )
    return seen


def test_laser_run_topics_decode_to_the_sdk_messages():
    seen = _compare_run(load_scenario("paper-side"), "laser", every=3)
    assert seen["scans"] > 0 and seen["arrows"] > 0 and seen["triangles"] > 0 and seen["texts"] > 0
    assert seen["transforms"] > 0


def test_front_run_candidates_and_via_points_decode_to_the_sdk_messages():
    seen = _compare_run(load_scenario("paper-front"), "oracle", every=2)
    assert seen["spheres"] > 0 and seen["lines"] > 100


def test_still_people_reuse_their_track_encoding_and_still_match():
    scenario = scenario_from_dict(
        {
            "name": "still-crowd",
            "dt_s": 0.1,
            "duration_s": 3.0,
            "robot": {"start": [0.0, 0.0], "heading": 0.0, "speed": 0.2, "radius": 0.25},
            "path": {"waypoints": [[0.0, 0.0], [6.0, 0.0]], "half_width": 1.5},
            "obstacles": [{"start": [3.0, 1.2 * (-1) ** k], "velocity": [0.0, 0.0], "radius": 0.25} for k in range(2)]
            + [{"start": [5.0, -1.0], "velocity": [-0.2, 0.1], "radius": 0.3}],
        }
    )
    seen = _compare_run(scenario, "oracle")
    assert seen["cylinders"] > 0
