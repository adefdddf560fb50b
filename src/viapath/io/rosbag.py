"""Read ``sensor_msgs/LaserScan`` (and ``geometry_msgs/PoseArray`` labels) from ROS 1 bags, ROS 2 bags and MCAP.

Source: the ``rosbags`` package (``rosbags.highlevel.AnyReader``), which reads ROS 1 ``.bag`` files,
ROS 2 bag directories and single ``.db3`` / ``.mcap`` storage files without a ROS installation.
It is an optional dependency: ``pip install 'viapath[ros]'``.

What we chose:
* Message times are the *header* stamps (bag record times can be meaningless: in the leg_tracker
  training bag they are compressed into 0.3 s); a zero header stamp falls back to the record time.
* Ranges are returned as recorded (0, NaN, ±inf, out-of-range included); the perception chain
  sanitises them (:func:`viapath.perception.scanner.sanitize_ranges`).
* A scan's beams ``angle_min + i · angle_increment`` become a :class:`ScannerModel` whose
  ``mount_yaw_rad`` is the middle beam's angle, so the beam angles are reproduced exactly.
* ROS 2 storage without embedded message definitions is decoded with the ``LATEST`` type store.
* A clockwise scan (negative ``angle_increment``) is reversed so that beams always turn
  counter-clockwise.
"""

from __future__ import annotations

import struct
import warnings
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

LASER_SCAN_TYPES = ("sensor_msgs/msg/LaserScan", "sensor_msgs/LaserScan")
POSE_ARRAY_TYPES = ("geometry_msgs/msg/PoseArray", "geometry_msgs/PoseArray")


class RosbagsMissingError(ImportError):
    """The optional ``rosbags`` package is not installed."""


class BagError(ValueError):
    """A recording that cannot be used; the message says why in one line."""


def _anyreader():
    try:
        from rosbags.highlevel import AnyReader
        from rosbags.typesys import Stores, get_typestore
    except ImportError as error:  # pragma: no cover - depends on the environment
        raise RosbagsMissingError(
            f"reading ROS bags needs the 'rosbags' package ({error}); install it with: pip install 'viapath[ros]'"
        ) from None
    return AnyReader, get_typestore(Stores.LATEST)


@dataclass(frozen=True)
class LaserScanMessage:
    """One ``sensor_msgs/LaserScan``, SI units."""

    stamp_s: float
    frame_id: str
    angle_min_rad: float
    angle_increment_rad: float
    range_min_m: float
    range_max_m: float
    ranges_m: np.ndarray
    scan_time_s: float = 0.0

    @property
    def beam_count(self) -> int:
        return len(self.ranges_m)

    def angles_rad(self) -> np.ndarray:
        return self.angle_min_rad + np.arange(self.beam_count) * self.angle_increment_rad

    def scanner_model(self, name: str | None = None):
        """A :class:`~viapath.perception.scanner.ScannerModel` with exactly this scan's beams, at the frame origin."""
        from viapath.perception.scanner import ScannerModel

        n = self.beam_count
        return ScannerModel(
            name=name or self.frame_id or "laser",
            mount_x_m=0.0,
            mount_y_m=0.0,
            mount_yaw_rad=self.angle_min_rad + 0.5 * (n - 1) * self.angle_increment_rad,
            beam_count=n,
            angle_increment_rad=abs(self.angle_increment_rad),
            range_min_m=max(self.range_min_m, 0.0),
            range_max_m=self.range_max_m,
            scan_period_s=self.scan_time_s if self.scan_time_s > 0 else 0.1,
        )


def _check_path(path) -> Path:
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such file or directory")
    return path


def _stamp(message, record_time_ns: int) -> float:
    header = getattr(message, "header", None)
    stamp = getattr(header, "stamp", None)
    if stamp is not None:
        seconds = float(getattr(stamp, "sec", 0)) + 1e-9 * float(getattr(stamp, "nanosec", 0))
        if seconds > 0:
            return seconds
    return 1e-9 * record_time_ns


def bag_topics(path) -> dict[str, str]:
    """Topic -> message type of every connection in the recording."""
    path = _check_path(path)
    AnyReader, typestore = _anyreader()
    try:
        with AnyReader([path], default_typestore=typestore) as reader:
            return {c.topic: c.msgtype for c in reader.connections}
    except (FileNotFoundError, RosbagsMissingError):
        raise
    except Exception as error:
        raise BagError(
            f"{path}: not a readable ROS 1/ROS 2 bag or MCAP file ({type(error).__name__}: {error})"
        ) from None


def _pick_topic(path: Path, topics: dict[str, str], topic: str | None, types, what: str) -> str:
    matching = sorted(t for t, msgtype in topics.items() if msgtype in types)
    if topic is not None:
        if topic not in topics:
            raise BagError(f"{path}: no topic {topic!r}; {what} topics: {', '.join(matching) or 'none'}")
        if topics[topic] not in types:
            raise BagError(f"{path}: topic {topic!r} holds {topics[topic]}, not {what}")
        return topic
    if not matching:
        raise BagError(f"{path}: no {what} topic (topics: {', '.join(sorted(topics)) or 'none'})")
    if len(matching) > 1:
        raise BagError(f"{path}: several {what} topics ({', '.join(matching)}); choose one with --topic")
    return matching[0]


def read_laser_scans(path, topic: str | None = None) -> Iterator[LaserScanMessage]:
    """Every LaserScan on ``topic`` (default: the only LaserScan topic), in recording order. An MCAP
    file cut off (a recording that was killed) or damaged is read up to the damage, with a
    :class:`BagWarning` saying so."""
    path = _check_path(path)
    try:
        topics = bag_topics(path)
    except BagError as error:
        if path.suffix.lower() != ".mcap":
            raise
        yield from _cut_mcap_scans(path, topic, str(error))
        return
    topic = _pick_topic(path, topics, topic, LASER_SCAN_TYPES, "sensor_msgs/LaserScan")
    AnyReader, typestore = _anyreader()
    with AnyReader([path], default_typestore=typestore) as reader:
        connections = [c for c in reader.connections if c.topic == topic]
        for connection, record_time_ns, raw in reader.messages(connections=connections):
            yield _laser_scan(reader.deserialize(raw, connection.msgtype), record_time_ns, path, topic)


def _laser_scan(m, record_time_ns: int, path: Path, topic: str) -> LaserScanMessage:
    ranges = np.asarray(m.ranges, dtype=float).copy()
    angle_min, increment = float(m.angle_min), float(m.angle_increment)
    for field_name, value in (("angle_min", angle_min), ("angle_increment", increment)):
        if not (np.isfinite(value) and (field_name == "angle_min" or value != 0.0)):
            raise BagError(
                f"{path}: {topic}: a LaserScan at {_stamp(m, record_time_ns):.3f} s has {field_name} "
                f"{value} rad; expected a finite number{' other than 0' if field_name != 'angle_min' else ''}"
            )
    if increment < 0:  # clockwise scanner: store it counter-clockwise
        ranges = ranges[::-1].copy()
        angle_min, increment = angle_min + (len(ranges) - 1) * increment, -increment
    return LaserScanMessage(
        stamp_s=_stamp(m, record_time_ns),
        frame_id=str(m.header.frame_id),
        angle_min_rad=angle_min,
        angle_increment_rad=increment,
        range_min_m=float(m.range_min),
        range_max_m=float(m.range_max),
        ranges_m=ranges,
        scan_time_s=float(m.scan_time),
    )


class BagWarning(UserWarning):
    """A recording read only in part (cut off or damaged); the message says where it stopped."""


_MCAP_MAGIC = b"\x89MCAP0\r\n"


def _mcap_records(data: memoryview) -> Iterator[tuple[int, memoryview]]:
    """(opcode, content) of each whole record of an MCAP record stream, up to the first cut-off one."""
    pos = 0
    while pos + 9 <= len(data):
        opcode = data[pos]
        (length,) = struct.unpack_from("<Q", data, pos + 1)
        content = data[pos + 9 : pos + 9 + length]
        if opcode == 0x06 and len(content) >= 32:  # a chunk: its records, as far as they reach
            yield opcode, content
        elif len(content) < length:
            return
        else:
            yield opcode, content
        pos += 9 + length


def _string(content: memoryview, at: int) -> tuple[str, int]:
    (length,) = struct.unpack_from("<I", content, at)
    return bytes(content[at + 4 : at + 4 + length]).decode("utf-8", "replace"), at + 4 + length


def _cut_mcap_scans(path: Path, topic: str | None, why: str) -> Iterator[LaserScanMessage]:
    """The LaserScans of an MCAP file that the full reader refuses: its records read one by one (chunks
    uncompressed; a compressed one ends the reading) up to the first one cut off."""
    _, typestore = _anyreader()
    data = memoryview(path.read_bytes())
    if bytes(data[:8]) != _MCAP_MAGIC:
        raise BagError(why)
    schemas: dict[int, str] = {}
    channels: dict[int, tuple[str, str]] = {}
    found: list[tuple[int, int, memoryview]] = []  # (channel, log time, data)
    stopped = "cut off"

    def walk(records: Iterator[tuple[int, memoryview]]) -> bool:
        nonlocal stopped
        for opcode, content in records:
            if opcode == 0x03:  # schema: id, name, ...
                (ident,) = struct.unpack_from("<H", content, 0)
                schemas[ident] = _string(content, 2)[0]
            elif opcode == 0x04:  # channel: id, schema id, topic, ...
                ident, schema = struct.unpack_from("<HH", content, 0)
                channels[ident] = (_string(content, 4)[0], schemas.get(schema, ""))
            elif opcode == 0x05:  # message: channel, sequence, log time, publish time, data
                channel, _sequence, log_time = struct.unpack_from("<HIQ", content, 0)
                found.append((channel, log_time, content[22:]))
            elif opcode == 0x06:
                compression, at = _string(content, 28)
                if compression:
                    stopped = f"a {compression}-compressed chunk"
                    return False
                (length,) = struct.unpack_from("<Q", content, at)
                inner = content[at + 8 : at + 8 + length]
                if not walk(_mcap_records(inner)) or len(inner) < length:
                    return False
        return True

    try:
        walk(_mcap_records(data[8:]))
    except (struct.error, UnicodeDecodeError):
        stopped = "a damaged record"
    scan_topics = sorted({t for t, msgtype in channels.values() if msgtype in LASER_SCAN_TYPES})
    if topic is None:
        if len(scan_topics) != 1:
            raise BagError(f"{why}; read in part: LaserScan topics {', '.join(scan_topics) or 'none'}")
        topic = scan_topics[0]
    warnings.warn(
        f"{path}: {stopped} ({why.split(': ', 1)[-1]}); read the {len(found)} messages before it",
        BagWarning,
        stacklevel=3,
    )
    for channel, log_time, raw in found:
        name, msgtype = channels.get(channel, ("", ""))
        if name == topic and msgtype in LASER_SCAN_TYPES:
            yield _laser_scan(typestore.deserialize_cdr(bytes(raw), "sensor_msgs/msg/LaserScan"), log_time, path, topic)


def read_pose_arrays(path, topic: str | None = None) -> list[tuple[float, np.ndarray]]:
    """Every ``geometry_msgs/PoseArray`` on ``topic`` as (stamp_s, (N, 2) x-y positions), in recording order."""
    path = _check_path(path)
    topics = bag_topics(path)
    topic = _pick_topic(path, topics, topic, POSE_ARRAY_TYPES, "geometry_msgs/PoseArray")
    AnyReader, typestore = _anyreader()
    out = []
    with AnyReader([path], default_typestore=typestore) as reader:
        connections = [c for c in reader.connections if c.topic == topic]
        for connection, record_time_ns, raw in reader.messages(connections=connections):
            m = reader.deserialize(raw, connection.msgtype)
            xy = np.array([[p.position.x, p.position.y] for p in m.poses], dtype=float).reshape(-1, 2)
            out.append((_stamp(m, record_time_ns), xy))
    return out
