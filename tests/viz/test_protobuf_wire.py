"""Our numpy protobuf encoding decodes to the same message as foxglove-sdk's own encoding."""

from __future__ import annotations

import numpy as np
import pytest

messages = pytest.importorskip("foxglove.messages", reason="needs the viz extra (foxglove-sdk)")
pytest.importorskip("google.protobuf", reason="needs protobuf (viz extra)")

from google.protobuf import descriptor_pb2, descriptor_pool, message_factory  # noqa: E402

from viapath.viz import protobuf_wire as wire  # noqa: E402


# foxglove.TriangleListPrimitive: pose 1, points 2, color 3, colors 4, indices 5
def triangle_list_primitive(vertices_xyz: np.ndarray, triangles: np.ndarray, color: bytes, pose: bytes) -> bytes:
    return (
        wire.message_field(1, pose)
        + wire.points_field(2, vertices_xyz)
        + wire.message_field(3, color)
        + wire.fixed32_packed_field(5, np.asarray(triangles).ravel())
    )


# foxglove.SceneUpdate: deletions 1, entities 2
def scene_update(deletions: list[bytes], entities: list[bytes]) -> bytes:
    return b"".join(wire.message_field(1, d) for d in deletions) + b"".join(wire.message_field(2, e) for e in entities)


def _scene_update_class():
    files = descriptor_pb2.FileDescriptorSet.FromString(messages.SceneUpdate.get_schema().data)
    pool = descriptor_pool.DescriptorPool()
    for file in files.file:
        pool.Add(file)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName("foxglove.SceneUpdate"))


def test_scene_update_matches_the_sdk_encoding():
    m = messages
    rng = np.random.default_rng(3)
    line_xyz, vertices = rng.normal(size=(7, 3)), rng.normal(size=(11, 3))
    triangles = rng.integers(0, 11, size=(9, 3))
    colour = m.Color(r=0.1, g=0.2, b=0.3, a=0.4)
    pose = m.Pose(position=m.Vector3(x=1.0, y=-2.0, z=0.5), orientation=m.Quaternion(x=0.0, y=0.0, z=0.6, w=0.8))
    stamp_ns = 12_300_000_000 + 45
    text = m.TextPrimitive(pose=pose, billboard=True, font_size=11.0, text="t = 2 s", color=colour)

    points = lambda a: [m.Point3(x=x, y=y, z=z) for x, y, z in a.tolist()]
    sdk = m.SceneUpdate(
        deletions=[m.SceneEntityDeletion(type=m.SceneEntityDeletionType.All)],
        entities=[
            m.SceneEntity(
                timestamp=m.Timestamp(12, 300_000_045),
                frame_id="xyt",
                id="person-4",
                lines=[
                    m.LinePrimitive(
                        type=m.LinePrimitiveLineType.LineLoop,
                        pose=pose,
                        thickness=0.02,
                        points=points(line_xyz),
                        color=colour,
                    )
                ],
                triangles=[
                    m.TriangleListPrimitive(
                        pose=pose, points=points(vertices), color=colour, indices=triangles.ravel().tolist()
                    )
                ],
                texts=[text],
            )
        ],
    ).encode()
    ours = scene_update(
        [m.SceneEntityDeletion(type=m.SceneEntityDeletionType.All).encode()],
        [
            wire.scene_entity(
                stamp_ns,
                "xyt",
                "person-4",
                lines=[wire.line_primitive(line_xyz, colour.encode(), pose.encode(), 0.02, wire.LINE_LOOP)],
                triangles=[triangle_list_primitive(vertices, triangles, colour.encode(), pose.encode())],
                other=m.SceneEntity(texts=[text]).encode(),
            )
        ],
    )
    cls = _scene_update_class()
    assert cls.FromString(ours) == cls.FromString(sdk)
    decoded = cls.FromString(ours)
    entity = decoded.entities[0]
    assert (entity.timestamp.seconds, entity.timestamp.nanos) == (12, 300_000_045)
    np.testing.assert_array_equal([(p.x, p.y, p.z) for p in entity.triangles[0].points], vertices)
    assert list(entity.triangles[0].indices) == triangles.ravel().tolist()


def test_varint_and_points_field_edges():
    assert wire.varint(0) == b"\x00" and wire.varint(127) == b"\x7f" and wire.varint(300) == b"\xac\x02"
    assert wire.points_field(5, np.zeros((0, 3))) == b""
    with pytest.raises(ValueError):
        wire.points_field(16, np.zeros((1, 3)))
