"""Message conversion between ROS 2 types and viapath's arrays, and the designated path from a file.

Source: REP 103 (x forward, y left, yaw counter-clockwise), REP 117 (LaserScan: NaN = erroneous,
+inf = no return), ``nav_msgs/Path``. Imports of ROS message modules are inside the functions so
that the pure helpers (yaw, path files) work without rclpy.

What we chose:
* Yaw from a quaternion is the rotation about z (roll and pitch are ignored: a planar robot). A
  quaternion that is not finite or not of unit length (within ``QUATERNION_TOLERANCE``; (0, 0, 0, 0)
  included) is no orientation: :func:`checked_yaw` refuses it rather than read some yaw from it.
* A path file is a built-in scenario name, a scenario YAML (its ``path:`` block, widths included),
  a YAML map ``{waypoints: [[x, y], ...], half_width: w}`` / a plain YAML list of [x, y], or a CSV
  / whitespace text of x y rows.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from viapath.static import MAX_STATIC_RADIUS_M, StaticLayer

MAX_MAP_COORDINATE_M = 1.0e6  # m: as the guard's bound on the robot's own position
MAX_MAP_SEGMENTS = 2_000_000  # runs of occupied cells a map may give (a large building gives far fewer)
QUATERNION_TOLERANCE = 0.01  # |norm - 1| above this is not a rotation (ROS producers normalise to ~1e-9)


class PathFileError(ValueError):
    """A path file that cannot be used; the message names the file."""


def yaw_from_quaternion(x: float, y: float, z: float, w: float) -> float:
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def checked_yaw(x: float, y: float, z: float, w: float) -> float:
    """Yaw of a unit quaternion; ``ValueError`` saying why for one that is not finite or not of unit length."""
    values = (float(x), float(y), float(z), float(w))
    if not all(math.isfinite(v) for v in values):
        raise ValueError(f"quaternion {values} is not finite")
    norm = math.sqrt(sum(v * v for v in values))
    if abs(norm - 1.0) > QUATERNION_TOLERANCE:
        raise ValueError(f"quaternion ({', '.join(f'{v:.4g}' for v in values)}) has length {norm:.4g}, not 1")
    return yaw_from_quaternion(*(v / norm for v in values))


def quaternion_from_yaw(yaw: float) -> tuple[float, float, float, float]:
    return 0.0, 0.0, math.sin(0.5 * yaw), math.cos(0.5 * yaw)


def stamp_seconds(stamp) -> float:
    return float(stamp.sec) + 1e-9 * float(stamp.nanosec)


def time_msg(seconds: float):
    from builtin_interfaces.msg import Time

    t = Time()
    seconds = max(float(seconds), 0.0)
    t.sec = int(math.floor(seconds))
    t.nanosec = min(int(round((seconds - t.sec) * 1e9)), 999_999_999)
    return t


def load_path_file(source: str) -> tuple[np.ndarray, list[float] | None]:
    """(waypoints (N, 2), half-widths per segment or None) from ``source`` (see module notes)."""
    from viapath.scenarios import ScenarioError, builtin_names, load_scenario

    if source in builtin_names():
        spec = load_scenario(source)
        return np.asarray(spec.path.waypoints, dtype=float), list(spec.path.widths())
    path = Path(source)
    if not path.is_file():
        raise PathFileError(f"{source}: no such path file (or built-in scenario)")
    from viapath.io.safe_read import MAX_YAML_BYTES, InputError, load_yaml, read_text_file

    try:
        text = read_text_file(path, MAX_YAML_BYTES, "path file")
    except InputError as error:
        raise PathFileError(str(error)) from None
    if path.suffix.lower() in (".yaml", ".yml"):
        try:
            data = load_yaml(text, source)
        except InputError as error:
            raise PathFileError(str(error)) from None
        if isinstance(data, dict) and "robot" in data:
            try:
                spec = load_scenario(path)
            except ScenarioError as error:
                raise PathFileError(str(error)) from None
            return np.asarray(spec.path.waypoints, dtype=float), list(spec.path.widths())
        widths = None
        if isinstance(data, dict):
            if "waypoints" not in data:
                raise PathFileError(f"{source}: expected a 'waypoints' list of [x, y]")
            if "half_widths" in data:
                widths = [float(w) for w in data["half_widths"]]
            elif "half_width" in data:
                widths = [float(data["half_width"])] * (len(data["waypoints"]) - 1)
            data = data["waypoints"]
        try:
            points = np.asarray(data, dtype=float)
        except (TypeError, ValueError):
            raise PathFileError(f"{source}: waypoints: expected a list of [x, y] numbers") from None
    else:
        try:
            points = np.loadtxt(path, delimiter="," if "," in text else None, ndmin=2)
        except ValueError as error:
            raise PathFileError(f"{source}: expected rows of x y numbers ({error})") from None
    if points.ndim != 2 or points.shape[1] != 2 or len(points) < 2 or not np.isfinite(points).all():
        raise PathFileError(
            f"{source}: waypoints: expected at least two finite [x, y] points, found shape {points.shape}"
        )
    if widths is not None and (len(widths) != len(points) - 1 or not all(math.isfinite(w) and w > 0 for w in widths)):
        raise PathFileError(f"{source}: half_widths: expected {len(points) - 1} positive numbers")
    return points, widths


def path_message(waypoints, frame_id: str, stamp):
    from geometry_msgs.msg import PoseStamped
    from nav_msgs.msg import Path as PathMsg

    msg = PathMsg()
    msg.header.frame_id = frame_id
    msg.header.stamp = stamp
    points = np.asarray(waypoints, dtype=float)
    for k, p in enumerate(points):
        pose = PoseStamped()
        pose.header = msg.header
        pose.pose.position.x, pose.pose.position.y = float(p[0]), float(p[1])
        nxt = points[min(k + 1, len(points) - 1)] - points[max(k + 1, 1) - 1]
        _, _, pose.pose.orientation.z, pose.pose.orientation.w = quaternion_from_yaw(math.atan2(nxt[1], nxt[0]))
        msg.poses.append(pose)
    return msg


def laser_scan(
    frame_id: str,
    stamp,
    angle_min: float,
    angle_increment: float,
    ranges,
    range_min: float,
    range_max: float,
    scan_time: float = 0.1,
):
    from sensor_msgs.msg import LaserScan

    msg = LaserScan()
    msg.header.frame_id = frame_id
    msg.header.stamp = stamp
    ranges = np.asarray(ranges, dtype=np.float32)
    msg.angle_min = float(angle_min)
    msg.angle_increment = float(angle_increment)
    msg.angle_max = float(angle_min + (len(ranges) - 1) * angle_increment)
    msg.time_increment = 0.0
    msg.scan_time = float(scan_time)
    msg.range_min, msg.range_max = float(range_min), float(range_max)
    msg.ranges = ranges  # numpy float32 is accepted as array('f') without a per-element copy
    return msg


def odometry(frame_id: str, child_frame_id: str, stamp, x: float, y: float, yaw: float, speed: float, turn_rate: float):
    from nav_msgs.msg import Odometry

    msg = Odometry()
    msg.header.frame_id = frame_id
    msg.header.stamp = stamp
    msg.child_frame_id = child_frame_id
    msg.pose.pose.position.x, msg.pose.pose.position.y = float(x), float(y)
    _, _, msg.pose.pose.orientation.z, msg.pose.pose.orientation.w = quaternion_from_yaw(yaw)
    msg.twist.twist.linear.x = float(speed)
    msg.twist.twist.angular.z = float(turn_rate)
    return msg


def odometry_values(msg) -> tuple[float, float, tuple[float, float, float, float], float, float]:
    """(x, y, quaternion (x, y, z, w), forward speed, turn rate) of a ``nav_msgs/Odometry`` (twist in the
    child frame); the quaternion is checked by the core (:func:`checked_yaw`)."""
    p, q, t = msg.pose.pose.position, msg.pose.pose.orientation, msg.twist.twist
    return (
        float(p.x),
        float(p.y),
        (float(q.x), float(q.y), float(q.z), float(q.w)),
        float(t.linear.x),
        float(t.angular.z),
    )


def occupancy_layer(
    cells: np.ndarray, resolution_m: float, origin_x: float, origin_y: float, origin_yaw: float, threshold: int = 65
) -> StaticLayer:
    """The occupied cells of an occupancy grid (``cells``: (height, width) of -1 unknown / 0-100) as static
    geometry in the grid's frame: each row's runs of occupied cells as one segment through their centres,
    a single cell as a point, each with the half-diagonal of a cell as its radius (so the segments with
    their radii cover every occupied cell)."""
    cells = np.asarray(cells)
    if cells.ndim != 2 or not (math.isfinite(resolution_m) and resolution_m > 0):
        raise ValueError(
            f"occupancy grid: expected (height, width) cells and a resolution > 0, found shape "
            f"{cells.shape}, resolution {resolution_m}"
        )
    # A map whose origin or far corner lies beyond any coordinate the guard accepts for the robot is no
    # map of where the robot is (a NaN or 1e300 origin would put every wall nowhere).
    extent = max(cells.shape) * resolution_m * math.sqrt(2.0)
    for name, value in (("origin.position.x", origin_x), ("origin.position.y", origin_y)):
        if not (math.isfinite(value) and abs(value) + extent <= MAX_MAP_COORDINATE_M):
            raise ValueError(
                f"occupancy grid: {name} {value:g} m: expected a finite number with the whole map within "
                f"±{MAX_MAP_COORDINATE_M:g} m"
            )
    if not math.isfinite(origin_yaw):
        raise ValueError(f"occupancy grid: origin yaw {origin_yaw:g} rad is not finite")
    if resolution_m * math.sqrt(0.5) > MAX_STATIC_RADIUS_M:
        raise ValueError(
            f"occupancy grid: resolution {resolution_m:g} m: cells larger than {MAX_STATIC_RADIUS_M * math.sqrt(2):g} m "
            "are no map"
        )
    rows_list, starts_list, ends_list, count = [], [], [], 0
    chunk = max(1, 4_000_000 // max(cells.shape[1], 1))  # rows at a time: memory bounded for any map
    for first in range(0, cells.shape[0], chunk):
        occupied = cells[first : first + chunk] >= threshold
        padded = np.zeros((occupied.shape[0], occupied.shape[1] + 2), dtype=np.int8)
        padded[:, 1:-1] = occupied
        change = np.diff(padded, axis=1)
        rows, starts = np.nonzero(change == 1)
        _, ends = np.nonzero(change == -1)  # row-major order pairs each start with its end
        count += len(rows)
        if count > MAX_MAP_SEGMENTS:
            raise ValueError(
                f"occupancy grid: more than {MAX_MAP_SEGMENTS:,} runs of occupied cells (a checkerboard, "
                "not a map of a building)"
            )
        rows_list.append(rows + first)
        starts_list.append(starts)
        ends_list.append(ends)
    if count == 0:
        return StaticLayer.empty()
    rows, starts, ends = np.concatenate(rows_list), np.concatenate(starts_list), np.concatenate(ends_list)
    local = (
        np.stack([np.stack([starts + 0.5, rows + 0.5], axis=1), np.stack([ends - 0.5, rows + 0.5], axis=1)], axis=1)
        * resolution_m
    )  # (S, 2, 2) cell centres, grid frame
    c, s = math.cos(origin_yaw), math.sin(origin_yaw)
    world = local @ np.array([[c, s], [-s, c]]) + np.array([origin_x, origin_y])
    return StaticLayer(world, np.arange(len(world)), np.full(len(world), resolution_m * math.sqrt(0.5)))


def occupancy_layer_from_message(msg, threshold: int = 65) -> StaticLayer:
    info = msg.info
    origin = info.origin
    q = origin.orientation
    height, width = int(info.height), int(info.width)
    data = msg.data
    try:  # int8[] arrives as an array.array: read in place (a 10 000 x 10 000 map is 100 MB)
        cells = np.frombuffer(data, dtype=np.int8)
    except (TypeError, ValueError):
        cells = np.asarray(data, dtype=np.int16)
    if cells.size != height * width:
        raise ValueError(f"occupancy grid: {cells.size} cells for width {width} x height {height}")
    cells = cells.reshape(height, width)
    return occupancy_layer(
        cells,
        float(info.resolution),
        float(origin.position.x),
        float(origin.position.y),
        checked_yaw(q.x, q.y, q.z, q.w),
        threshold,
    )
