"""Protobuf wire format for the vertex-heavy Foxglove messages, vectorised with numpy.

Source: the protobuf encoding specification (varints, tags ``field << 3 | wire type``, length-
delimited sub-messages, packed repeated scalars) and the field numbers of Foxglove's schemas
(``foxglove/SceneUpdate.proto`` and the primitives it holds, as stored in the MCAP schema record).
Why: building one Python object per vertex (``foxglove.messages.Point3``) cost about a microsecond
each; a person's x-y-t cylinder has ~50 vertices, a cycle's candidates hundreds. Here a whole
point list is one structured numpy array turned into bytes.

What we chose:
* Only what the views need: ``SceneUpdate`` with deletions and entities; entities with
  ``LinePrimitive`` and ``TriangleListPrimitive`` written here and every other primitive taken
  from foxglove-sdk's own ``encode()`` (protobuf concatenates repeated fields, so the parts join).
* Every double is written, zeros included (proto3 allows it; decoders read the same values).
* Tests decode what this writes with the schema from the file (``tests/viz``) and compare with the
  SDK's own encoding of the same message.
"""

from __future__ import annotations

import struct

import numpy as np

_POINT = np.dtype([("tag", "u1"), ("length", "u1"), ("tx", "u1"), ("x", "<f8"), ("ty", "u1"), ("y", "<f8"),
                   ("tz", "u1"), ("z", "<f8")])  # packed: 29 bytes, one length-delimited Point3


_SMALL = [bytes((i,)) for i in range(128)]


def varint(value: int) -> bytes:
    if 0 <= value < 128:
        return _SMALL[value]
    value = int(value)
    if value < 0:
        value += 1 << 64
    out = bytearray()
    while True:
        byte = value & 0x7F
        value >>= 7
        if value:
            out.append(byte | 0x80)
        else:
            out.append(byte)
            return bytes(out)


def tag(field: int, wire_type: int) -> bytes:
    return _SMALL[field << 3 | wire_type] if field < 16 else varint(field << 3 | wire_type)


def message_field(field: int, payload: bytes) -> bytes:
    """A length-delimited field (sub-message, string, bytes, packed scalars)."""
    return tag(field, 2) + varint(len(payload)) + payload


def double_field(field: int, value: float) -> bytes:
    return tag(field, 1) + struct.pack("<d", float(value))


def varint_field(field: int, value: int) -> bytes:
    return tag(field, 0) + varint(value)


def string_field(field: int, text: str) -> bytes:
    return message_field(field, text.encode("utf-8"))


def points_field(field: int, xyz: np.ndarray) -> bytes:
    """A repeated ``Point3`` field (field number < 16) from an (N, 3) array."""
    if not 0 < field < 16:
        raise ValueError("points_field handles field numbers 1..15")
    xyz = np.asarray(xyz, dtype=float).reshape(-1, 3)
    rows = np.empty(len(xyz), dtype=_POINT)
    rows["tag"] = field << 3 | 2
    rows["length"] = 27
    rows["tx"], rows["ty"], rows["tz"] = 0x09, 0x11, 0x19
    rows["x"], rows["y"], rows["z"] = xyz[:, 0], xyz[:, 1], xyz[:, 2]
    return rows.tobytes()


def fixed32_packed_field(field: int, values: np.ndarray) -> bytes:
    """A packed repeated ``fixed32`` field (the primitives' ``indices``)."""
    data = np.asarray(values, dtype="<u4").tobytes()
    return message_field(field, data) if data else b""


def timestamp(ns: int) -> bytes:
    """google.protobuf.Timestamp: seconds (1), nanos (2)."""
    seconds, nanos = divmod(int(ns), 1_000_000_000)
    return (varint_field(1, seconds) if seconds else b"") + (varint_field(2, nanos) if nanos else b"")


# foxglove.LinePrimitive: type 1, pose 2, thickness 3, scale_invariant 4, points 5, color 6, colors 7, indices 8
LINE_STRIP, LINE_LOOP, LINE_LIST = 0, 1, 2


def line_primitive(points_xyz: np.ndarray, color: bytes, pose: bytes, thickness: float, kind: int = LINE_STRIP,
                   indices: np.ndarray | None = None) -> bytes:
    """An encoded ``foxglove.LinePrimitive``; ``color`` and ``pose`` are encoded sub-messages."""
    return (varint_field(1, kind) + message_field(2, pose) + double_field(3, thickness)
            + points_field(5, points_xyz) + message_field(6, color)
            + (fixed32_packed_field(8, indices) if indices is not None else b""))


# foxglove.TriangleListPrimitive: pose 1, points 2, color 3, colors 4, indices 5
def triangle_list_primitive(vertices_xyz: np.ndarray, triangles: np.ndarray, color: bytes, pose: bytes) -> bytes:
    return (message_field(1, pose) + points_field(2, vertices_xyz) + message_field(3, color)
            + fixed32_packed_field(5, np.asarray(triangles).ravel()))


# foxglove.SceneEntity: timestamp 1, frame_id 2, id 3, lifetime 4, frame_locked 5, metadata 6, arrows 7,
# cubes 8, spheres 9, cylinders 10, lines 11, triangles 12, texts 13, models 14
ENTITY_LINES, ENTITY_TRIANGLES = 11, 12


def scene_entity(stamp_ns: int, frame_id: str, entity_id: str, lines: list[bytes] = (), triangles: list[bytes] = (),
                 other: bytes = b"") -> bytes:
    """An encoded ``foxglove.SceneEntity``; ``other``: the SDK's encoding of an entity holding the
    remaining primitives (spheres, texts, ...), which protobuf merges into this one."""
    head = message_field(1, timestamp(stamp_ns)) + string_field(2, frame_id) + string_field(3, entity_id)
    return (head + b"".join(message_field(ENTITY_LINES, line) for line in lines)
            + b"".join(message_field(ENTITY_TRIANGLES, tri) for tri in triangles) + other)


# foxglove.SceneUpdate: deletions 1, entities 2
def scene_update(deletions: list[bytes], entities: list[bytes]) -> bytes:
    return b"".join(message_field(1, d) for d in deletions) + b"".join(message_field(2, e) for e in entities)
