"""Protobuf wire format for the Foxglove messages written every cycle, with struct and numpy.

Source: the protobuf encoding specification (varints, tags ``field << 3 | wire type``, length-
delimited sub-messages, packed repeated scalars) and the field numbers of Foxglove's schemas
(``foxglove/SceneUpdate.proto``, ``LaserScan.proto``, ``FrameTransforms.proto`` and what they
hold, as stored in the MCAP schema record). Why: building one Python object per vertex or field
(``foxglove.messages.Point3``, ``Pose``, ...) cost about a microsecond each; a person's x-y-t
cylinder has ~50 vertices, a cycle's candidates hundreds, and the writer's CPU per cycle is what
an MCAP costs a run. Here a point list is one structured numpy array turned into bytes
(up to 8 points, one ``struct.pack`` each), a pose one ``struct.pack``.

What we chose:
* Only what the views need: ``SceneUpdate`` with deletions and entities; entities with
  ``LinePrimitive``, ``TriangleListPrimitive``, ``CylinderPrimitive``, ``SpherePrimitive``,
  ``ArrowPrimitive`` and ``TextPrimitive``; ``LaserScan``; ``FrameTransforms``. Anything else (and
  any part that is the same all run: colours, the identity pose, static entities) is taken from
  foxglove-sdk's own ``encode()`` (protobuf concatenates fields, so the parts join).
* What repeats is encoded once: a cycle's timestamp field, an entity's frame and id, a label's
  text after its pose (``lru_cache``).
* Every double is written, zeros included (proto3 allows it; decoders read the same values).
* Tests decode what this writes with the schema (``tests/viz/test_protobuf_wire.py``,
  ``tests/viz/test_wire_topics.py``) and compare it, field by field, with the message
  foxglove-sdk's classes build.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Sequence
from functools import lru_cache

import numpy as np

_POINT = np.dtype(
    [
        ("tag", "u1"),
        ("length", "u1"),
        ("tx", "u1"),
        ("x", "<f8"),
        ("ty", "u1"),
        ("y", "<f8"),
        ("tz", "u1"),
        ("z", "<f8"),
    ]
)  # packed: 29 bytes, one length-delimited Point3
POINT_DTYPE = _POINT
_POINT_STRUCT = struct.Struct("<BBBdBdBd")  # the same 29 bytes


_SMALL = [bytes((i,)) for i in range(128)]


def varint(value: int) -> bytes:
    if 0 <= value < 128:
        return _SMALL[value]
    if 0 <= value < 16384:  # two bytes: the length of most sub-messages here
        return bytes((value & 0x7F | 0x80, value >> 7))
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


_LENGTH_DELIMITED = [tag(field, 2) for field in range(16)]


def message_field(field: int, payload: bytes) -> bytes:
    """A length-delimited field (sub-message, string, bytes, packed scalars)."""
    size = len(payload)
    if size < 128:  # the common case in one step: a one-byte tag and a one-byte length
        return _LENGTH_DELIMITED[field] + _SMALL[size] + payload
    return tag(field, 2) + varint(size) + payload


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
    if len(xyz) <= 8:  # a few points: one struct.pack each is cheaper than numpy's per-call cost
        head = field << 3 | 2
        return b"".join(_POINT_STRUCT.pack(head, 27, 0x09, x, 0x11, y, 0x19, z) for x, y, z in xyz.tolist())
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


@lru_cache(maxsize=4)
def stamp_field(ns: int) -> bytes:
    """Field 1 holding the timestamp ``ns``: every message of a cycle has the same one."""
    return message_field(1, timestamp(ns))


# foxglove.LinePrimitive: type 1, pose 2, thickness 3, scale_invariant 4, points 5, color 6, colors 7, indices 8
LINE_STRIP, LINE_LOOP, LINE_LIST = 0, 1, 2


def line_primitive(
    points_xyz: np.ndarray,
    color: bytes,
    pose: bytes,
    thickness: float,
    kind: int = LINE_STRIP,
    indices: np.ndarray | None = None,
) -> bytes:
    """An encoded ``foxglove.LinePrimitive``; ``color`` and ``pose`` are encoded sub-messages."""
    return (
        varint_field(1, kind)
        + message_field(2, pose)
        + double_field(3, thickness)
        + points_field(5, points_xyz)
        + message_field(6, color)
        + (fixed32_packed_field(8, indices) if indices is not None else b"")
    )


# foxglove.SceneEntity: timestamp 1, frame_id 2, id 3, lifetime 4, frame_locked 5, metadata 6, arrows 7,
# cubes 8, spheres 9, cylinders 10, lines 11, triangles 12, texts 13, models 14
ENTITY_LINES, ENTITY_TRIANGLES = 11, 12  # with ENTITY_ARROWS ... below


def scene_entity(
    stamp_ns: int,
    frame_id: str,
    entity_id: str,
    lines: Sequence[bytes] = (),
    triangles: Sequence[bytes] = (),
    other: bytes = b"",
) -> bytes:
    """An encoded ``foxglove.SceneEntity``; ``other``: the SDK's encoding of an entity holding the
    remaining primitives (spheres, texts, ...), which protobuf merges into this one."""
    head = stamp_field(stamp_ns) + _names(frame_id, entity_id, False)
    return (
        head
        + b"".join(message_field(ENTITY_LINES, line) for line in lines)
        + b"".join(message_field(ENTITY_TRIANGLES, tri) for tri in triangles)
        + other
    )


# -- small messages as one struct.pack each (every tag and length is a single byte here) -----------
# foxglove.Vector3 / Point3: x 1, y 2, z 3; Quaternion: x 1, y 2, z 3, w 4; Pose: position 1, orientation 2
_VECTOR3 = struct.Struct("<BdBdBd")  # 27 bytes
_POSE = struct.Struct("<BBBdBdBdBBBdBdBdBd")  # 67 bytes: position (2 + 27) and orientation (2 + 36)


def vector3(x: float, y: float, z: float) -> bytes:
    """An encoded ``foxglove.Vector3`` (27 bytes)."""
    return _VECTOR3.pack(0x09, x, 0x11, y, 0x19, z)


def pose(x: float, y: float, z: float = 0.0, yaw_rad: float = 0.0) -> bytes:
    """An encoded ``foxglove.Pose`` at (x, y, z) turned by ``yaw_rad`` about z (67 bytes)."""
    half = 0.5 * yaw_rad
    return _POSE.pack(
        0x0A, 27, 0x09, x, 0x11, y, 0x19, z, 0x12, 36, 0x09, 0.0, 0x11, 0.0, 0x19, math.sin(half), 0x21, math.cos(half)
    )


_POSE_1, _SIZE_2 = b"\x0a\x43", b"\x12\x1b"  # field 1 of 67 bytes (pose), field 2 of 27 bytes (size)


# foxglove.CylinderPrimitive: pose 1, size 2, bottom_scale 3, top_scale 4, color 5
def cylinder(pose_bytes: bytes, size_x: float, size_y: float, size_z: float, color: bytes) -> bytes:
    """An encoded ``CylinderPrimitive`` (``pose_bytes``: :func:`pose`; ``color``: an encoded Color)."""
    return _POSE_1 + pose_bytes + _SIZE_2 + vector3(size_x, size_y, size_z) + message_field(5, color)


# A CylinderPrimitive standing upright (yaw 0): its pose and size in one struct.pack.
_UPRIGHT = struct.Struct("<BB" + "BBBdBdBdBBBdBdBdBd" + "BBBdBdBd")


def upright_cylinder(
    x: float, y: float, z: float, size_x: float, size_y: float, size_z: float, color_field: bytes
) -> bytes:
    """:func:`cylinder` with the pose ``pose(x, y, z)``; ``color_field``: ``message_field(5, color)``."""
    return (
        _UPRIGHT.pack(
            0x0A,
            67,
            0x0A,
            27,
            0x09,
            x,
            0x11,
            y,
            0x19,
            z,
            0x12,
            36,
            0x09,
            0.0,
            0x11,
            0.0,
            0x19,
            0.0,
            0x21,
            1.0,
            0x12,
            27,
            0x09,
            size_x,
            0x11,
            size_y,
            0x19,
            size_z,
        )
        + color_field
    )


# foxglove.SpherePrimitive: pose 1, size 2, color 3
def sphere(pose_bytes: bytes, size: bytes, color: bytes) -> bytes:
    """An encoded ``SpherePrimitive`` (``size``: :func:`vector3`)."""
    return _POSE_1 + pose_bytes + _SIZE_2 + size + message_field(3, color)


# foxglove.ArrowPrimitive: pose 1, shaft_length 2, shaft_diameter 3, head_length 4, head_diameter 5, color 6
_ARROW = struct.Struct("<BdBdBdBd")


def arrow(
    pose_bytes: bytes,
    shaft_length: float,
    shaft_diameter: float,
    head_length: float,
    head_diameter: float,
    color: bytes,
) -> bytes:
    return (
        _POSE_1
        + pose_bytes
        + _ARROW.pack(0x11, shaft_length, 0x19, shaft_diameter, 0x21, head_length, 0x29, head_diameter)
        + message_field(6, color)
    )


# foxglove.TextPrimitive: pose 1, billboard 2, font_size 3, scale_invariant 4, color 5, text 6
def text(
    pose_bytes: bytes,
    content: str,
    font_size: float,
    color: bytes,
    billboard: bool = True,
    scale_invariant: bool = True,
) -> bytes:
    return _POSE_1 + pose_bytes + _text_tail(content, font_size, color, billboard, scale_invariant)


@lru_cache(maxsize=1024)
def _text_tail(content: str, font_size: float, color: bytes, billboard: bool, scale_invariant: bool) -> bytes:
    """Everything of a TextPrimitive after its pose: the same for a label drawn again elsewhere."""
    return (
        varint_field(2, int(billboard))
        + double_field(3, font_size)
        + varint_field(4, int(scale_invariant))
        + message_field(5, color)
        + string_field(6, content)
    )


ENTITY_ARROWS, ENTITY_SPHERES, ENTITY_CYLINDERS, ENTITY_TEXTS = 7, 9, 10, 13


def entity_head(stamp_ns: int | None, frame_id: str, entity_id: str, frame_locked: bool = False) -> bytes:
    """The fields of a ``SceneEntity`` before its primitives (no timestamp when ``stamp_ns`` is None)."""
    return (b"" if stamp_ns is None else stamp_field(stamp_ns)) + _names(frame_id, entity_id, frame_locked)


@lru_cache(maxsize=1024)
def _names(frame_id: str, entity_id: str, frame_locked: bool) -> bytes:
    """A SceneEntity's frame, id and frame_locked: the same for a given entity every cycle."""
    return string_field(2, frame_id) + string_field(3, entity_id) + (varint_field(5, 1) if frame_locked else b"")


def primitives(field: int, encoded: list[bytes]) -> bytes:
    """Repeated primitives of one kind in an entity (``field``: ``ENTITY_*``)."""
    return b"".join(message_field(field, one) for one in encoded)


# foxglove.LaserScan: timestamp 1, frame_id 2, pose 3, start_angle 4, end_angle 5, ranges 6, intensities 7
def laser_scan(
    stamp_ns: int, frame_id: str, pose_bytes: bytes, start_angle: float, end_angle: float, ranges: np.ndarray
) -> bytes:
    """An encoded ``foxglove.LaserScan`` (``pose_bytes``: an encoded Pose; ranges packed as doubles)."""
    data = np.asarray(ranges, dtype="<f8").tobytes()
    return (
        stamp_field(stamp_ns)
        + string_field(2, frame_id)
        + message_field(3, pose_bytes)
        + double_field(4, start_angle)
        + double_field(5, end_angle)
        + (message_field(6, data) if data else b"")
    )


# foxglove.FrameTransform: timestamp 1, parent_frame_id 2, child_frame_id 3, translation 4, rotation 5
_QUATERNION = struct.Struct("<BdBdBdBd")  # 36 bytes


def frame_transform_tail(parent: str, child: str, x: float, y: float, yaw_rad: float) -> bytes:
    """An encoded ``foxglove.FrameTransform`` after its timestamp: ``child`` at (x, y, 0) in
    ``parent``, turned by ``yaw_rad`` about z (prepend :func:`stamp_field`)."""
    half = yaw_rad / 2
    return (
        string_field(2, parent)
        + string_field(3, child)
        + b"\x22\x1b"
        + vector3(x, y, 0.0)
        + b"\x2a\x24"
        + _QUATERNION.pack(0x09, 0.0, 0x11, 0.0, 0x19, math.sin(half), 0x21, math.cos(half))
    )


# foxglove.FrameTransforms: transforms 1
def frame_transforms(transforms: list[bytes]) -> bytes:
    return b"".join(message_field(1, transform) for transform in transforms)
