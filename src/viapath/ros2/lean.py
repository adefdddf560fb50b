"""Big messages taken as numpy arrays: a ``nav_msgs/Path`` (on a topic, or in a FollowPath goal) with no Python
object per pose, a ``nav_msgs/OccupancyGrid`` with its cells copied while the interpreter runs on.

Source: rclpy (Kilted) makes a Python message of a taken C message with the conversion its type support names
(``_CONVERT_TO_PY`` on the message class, a C function called with the C message); the C message is rosidl's C
struct (``std_msgs__msg__Header``, ``geometry_msgs__msg__PoseStamped``, ``rosidl_runtime_c__String``, sequences as
data / size / capacity). For a path of N poses that conversion makes about 7 N Python objects under the GIL: 2–4 s
for 100 000 poses, and the cyclic garbage collector's full passes that so many new objects set off stop every other
thread of the process (the control loop) for 0.1–0.3 s at a time.

What we chose:
* A *lean* message class: the real message's type support and its creation and destruction of the C message, with a
  conversion of our own (a ctypes callback) that copies the poses' positions and orientations out of the C array
  with one strided numpy copy each, and returns a :class:`PathArrays`. rclpy takes it as it takes the real class
  (subscriptions, and the goal request of :class:`LeanGoalActionServer`): 100 000 poses are taken in 12–30 ms,
  the middleware's own deserialisation included.
* The C layout is written out below as ctypes structures; :func:`lean_path_type` and :func:`lean_goal_request_type`
  check it when they are made, by decoding a known message both ways. Where they differ (a build with another
  layout) they return None and the caller takes the ordinary Python messages: slow, but right.
* An occupancy grid's cells (10⁸ for a 10 000 x 10 000 map) are copied out of the C message by ``ctypes.memmove``,
  which runs without the GIL, instead of into an ``array.array`` under it: the control loop goes on meanwhile.
  rclpy holds the GIL through the middleware's own deserialisation too (``rcl_take``: 0.1–0.2 s for 100 MB), so
  :class:`TakenAside` takes such a topic in a thread of its own that calls ``rcl_take`` through ctypes (a
  foreign call, without the GIL) on a subscription of rclpy's that no executor sees, polled every 0.1 s.
* The conversion never raises (a ctypes callback that raises would hand rclpy a NULL message): what cannot be read
  becomes a value whose ``error`` says why (a :class:`PathArrays`, a grid), refused by the caller with that message.
* Only the goal's id and its path are read from a FollowPath goal request (the path is the goal's first field in
  every Nav2 release); the controller and checker ids are not used by the node.
"""

from __future__ import annotations

import ctypes
import math
import re
from dataclasses import dataclass
from types import SimpleNamespace
from typing import Any

import numpy as np


class _String(ctypes.Structure):
    _fields_ = [("data", ctypes.c_void_p), ("size", ctypes.c_size_t), ("capacity", ctypes.c_size_t)]


class _Time(ctypes.Structure):
    _fields_ = [("sec", ctypes.c_int32), ("nanosec", ctypes.c_uint32)]


class _Header(ctypes.Structure):
    _fields_ = [("stamp", _Time), ("frame_id", _String)]


class _Pose(ctypes.Structure):
    _fields_ = [("position", ctypes.c_double * 3), ("orientation", ctypes.c_double * 4)]


class _PoseStamped(ctypes.Structure):
    _fields_ = [("header", _Header), ("pose", _Pose)]


class _Sequence(ctypes.Structure):
    _fields_ = [("data", ctypes.c_void_p), ("size", ctypes.c_size_t), ("capacity", ctypes.c_size_t)]


class _Path(ctypes.Structure):
    _fields_ = [("header", _Header), ("poses", _Sequence)]


class _MapMetaData(ctypes.Structure):
    _fields_ = [
        ("map_load_time", _Time),
        ("resolution", ctypes.c_float),
        ("width", ctypes.c_uint32),
        ("height", ctypes.c_uint32),
        ("origin", _Pose),
    ]


class _OccupancyGrid(ctypes.Structure):
    _fields_ = [("header", _Header), ("info", _MapMetaData), ("data", _Sequence)]


class _GoalRequest(ctypes.Structure):
    """``nav2_msgs/action/FollowPath_SendGoal_Request``: the goal id, then the goal, whose first field is the path."""

    _fields_ = [("goal_id", ctypes.c_uint8 * 16), ("path", _Path)]


_POSE_BYTES = ctypes.sizeof(_PoseStamped)
_POSITION_AT = _PoseStamped.pose.offset + _Pose.position.offset
_ORIENTATION_AT = _PoseStamped.pose.offset + _Pose.orientation.offset
_CONVERT = ctypes.CFUNCTYPE(ctypes.py_object, ctypes.c_void_p)
MAX_FRAME_ID_BYTES = 4096  # a frame id is a short name; a longer one is read up to this


@dataclass(frozen=True)
class PathArrays:
    """A path's poses as arrays: what the node reads of a ``nav_msgs/Path``."""

    frame_id: str  # the header's
    stamp_s: float
    positions: np.ndarray  # (N, 2) x, y in m
    orientations: np.ndarray  # (N, 4) quaternions x, y, z, w
    first_pose_frame_id: str = ""
    error: str = ""  # why the poses could not be read ('' when they were)

    def __len__(self) -> int:
        return len(self.positions)

    @classmethod
    def of(cls, msg: Any) -> PathArrays:
        """The arrays of ``msg``: itself when it is one, else read from a Python ``nav_msgs/Path`` (one pose at a time)."""
        if isinstance(msg, PathArrays):
            return msg
        poses = msg.poses
        positions = np.array([[p.pose.position.x, p.pose.position.y] for p in poses], dtype=float).reshape(-1, 2)
        orientations = np.array(
            [[p.pose.orientation.x, p.pose.orientation.y, p.pose.orientation.z, p.pose.orientation.w] for p in poses],
            dtype=float,
        ).reshape(-1, 4)
        stamp = msg.header.stamp
        first = poses[0].header.frame_id if len(poses) else ""
        return cls(msg.header.frame_id, stamp.sec + 1e-9 * stamp.nanosec, positions, orientations, first)


@dataclass
class LeanGoal:
    """A FollowPath goal as the node reads it (``handle.request``)."""

    path: PathArrays


@dataclass
class LeanGoalRequest:
    """A FollowPath goal request as rclpy's action server needs it: ``goal_id`` (a UUID message) and ``goal``."""

    goal_id: Any
    goal: LeanGoal


def _unreadable(why: str) -> PathArrays:
    return PathArrays("", 0.0, np.zeros((0, 2)), np.zeros((0, 4)), error=why)


def _text(s: _String) -> str:
    if not s.data or not s.size:
        return ""
    return ctypes.string_at(s.data, min(int(s.size), MAX_FRAME_ID_BYTES)).decode("utf-8", "replace")


def _path_arrays(path: _Path) -> PathArrays:
    """The arrays of a C ``nav_msgs__msg__Path`` (copies: the C message is destroyed after the conversion)."""
    n = int(path.poses.size)
    if n and not path.poses.data:
        return _unreadable(f"{n} poses announced and none there")
    if n:
        block = memoryview((ctypes.c_char * (n * _POSE_BYTES)).from_address(path.poses.data))
        positions = np.ndarray((n, 2), np.float64, block, _POSITION_AT, (_POSE_BYTES, 8)).copy()
        orientations = np.ndarray((n, 4), np.float64, block, _ORIENTATION_AT, (_POSE_BYTES, 8)).copy()
        first = _text(_PoseStamped.from_address(path.poses.data).header.frame_id)
    else:
        positions, orientations, first = np.zeros((0, 2)), np.zeros((0, 4)), ""
    stamp = path.header.stamp
    return PathArrays(_text(path.header.frame_id), stamp.sec + 1e-9 * stamp.nanosec, positions, orientations, first)


def _path_from_c(address: int) -> PathArrays:
    try:
        return _path_arrays(_Path.from_address(address))
    except Exception as error:  # never out of the callback (see the module's notes)
        return _unreadable(f"{type(error).__name__}: {error}")


def _goal_request_from_c(address: int) -> LeanGoalRequest:
    from unique_identifier_msgs.msg import UUID

    try:
        request = _GoalRequest.from_address(address)
        goal_id = UUID(uuid=np.frombuffer(bytes(request.goal_id), dtype=np.uint8).copy())
    except Exception as error:  # never out of the callback (see the module's notes)
        return LeanGoalRequest(UUID(), LeanGoal(_unreadable(f"goal id: {type(error).__name__}: {error}")))
    return LeanGoalRequest(goal_id, LeanGoal(_path_from_c(address + _GoalRequest.path.offset)))


def grid_from_c(address: int) -> SimpleNamespace:
    """An occupancy grid with the fields the node reads (``header.frame_id``, ``info``, ``data`` as int8 cells);
    ``error`` says why the cells could not be read ('' when they were)."""
    try:
        grid = _OccupancyGrid.from_address(address)
        info, n = grid.info, int(grid.data.size)
        if n and not grid.data.data:
            raise ValueError(f"{n} cells announced and none there")
        cells = np.empty(n, dtype=np.int8)
        if n:
            ctypes.memmove(cells.ctypes.data, grid.data.data, n)  # a foreign call: without the GIL
        position, orientation = info.origin.position, info.origin.orientation
        return SimpleNamespace(
            header=SimpleNamespace(frame_id=_text(grid.header.frame_id)),
            info=SimpleNamespace(
                resolution=float(info.resolution),
                width=int(info.width),
                height=int(info.height),
                origin=SimpleNamespace(
                    position=SimpleNamespace(x=position[0], y=position[1], z=position[2]),
                    orientation=SimpleNamespace(x=orientation[0], y=orientation[1], z=orientation[2], w=orientation[3]),
                ),
            ),
            data=cells,
            error="",
        )
    except Exception as error:  # never out of the callback (see the module's notes)
        return SimpleNamespace(header=SimpleNamespace(frame_id=""), error=f"{type(error).__name__}: {error}")


def _capsule(function) -> Any:
    new = ctypes.pythonapi.PyCapsule_New
    new.restype = ctypes.py_object
    new.argtypes = [ctypes.c_void_p, ctypes.c_char_p, ctypes.c_void_p]
    return new(ctypes.cast(function, ctypes.c_void_p), None, None)


def _lean_class(real: Any, name: str, read) -> Any:
    """A class rclpy takes as ``real`` (same type support, C message made and destroyed alike) whose taken
    messages are ``read(address of the C message)``."""
    from rclpy.type_support import check_for_type_support

    check_for_type_support(real)
    converter = _CONVERT(read)
    attributes = {
        key: getattr(real, key)
        for key in ("_TYPE_SUPPORT", "_CREATE_ROS_MESSAGE", "_DESTROY_ROS_MESSAGE", "_CONVERT_FROM_PY")
    }
    attributes.update(_CONVERT_TO_PY=_capsule(converter), _converter=converter)  # the callback lives with the class
    meta = type(f"{name}Type", (type,), attributes)
    return meta(name, (), {"__doc__": f"{real.__name__} taken as arrays ({__name__})"})


def _same(lean: PathArrays, reference: PathArrays) -> bool:
    return (
        not lean.error
        and lean.frame_id == reference.frame_id
        and lean.first_pose_frame_id == reference.first_pose_frame_id
        and math.isclose(lean.stamp_s, reference.stamp_s, abs_tol=1e-9)
        and np.array_equal(lean.positions, reference.positions)
        and np.array_equal(lean.orientations, reference.orientations)
    )


def _sample_path(path: Any) -> Any:
    """A path with distinct values in every field the lean conversion reads."""
    from geometry_msgs.msg import PoseStamped

    path.header.frame_id = "map"
    path.header.stamp.sec, path.header.stamp.nanosec = 12, 345
    for k in range(3):
        pose = PoseStamped()
        pose.header.frame_id = "odom" if k == 0 else f"other{k}"
        pose.pose.position.x, pose.pose.position.y, pose.pose.position.z = 1.5 + k, -2.25 * k, 7.0
        pose.pose.orientation.x, pose.pose.orientation.y = 0.1 * k, 0.2
        pose.pose.orientation.z, pose.pose.orientation.w = 0.3, 0.9 - 0.1 * k
        path.poses.append(pose)
    return path


def lean_path_type() -> Any | None:
    """A ``nav_msgs/Path`` class whose taken messages are :class:`PathArrays`; None when the layout check fails."""
    from nav_msgs.msg import Path
    from rclpy.serialization import deserialize_message, serialize_message

    lean = _lean_class(Path, "LeanPath", _path_from_c)
    sample = _sample_path(Path())
    taken = deserialize_message(serialize_message(sample), lean)
    return lean if isinstance(taken, PathArrays) and _same(taken, PathArrays.of(sample)) else None


def lean_grid_type() -> Any | None:
    """A ``nav_msgs/OccupancyGrid`` class whose taken messages carry their cells as an int8 array (see
    :func:`grid_from_c`); None when the layout check fails."""
    import array

    from nav_msgs.msg import OccupancyGrid
    from rclpy.serialization import deserialize_message, serialize_message

    lean = _lean_class(OccupancyGrid, "LeanOccupancyGrid", grid_from_c)
    sample = OccupancyGrid()
    sample.header.frame_id = "odom"
    sample.info.resolution, sample.info.width, sample.info.height = 0.25, 3, 2
    o = sample.info.origin
    o.position.x, o.position.y, o.position.z = -1.5, 2.5, 0.5
    o.orientation.x, o.orientation.y, o.orientation.z, o.orientation.w = 0.0, 0.1, 0.2, 0.97
    sample.data = array.array("b", [0, 100, -1, 65, 7, -128])
    taken = deserialize_message(serialize_message(sample), lean)
    ok = (
        not taken.error
        and taken.header.frame_id == "odom"
        and (taken.info.resolution, taken.info.width, taken.info.height) == (0.25, 3, 2)
        and (taken.info.origin.position.x, taken.info.origin.position.y) == (-1.5, 2.5)
        and (taken.info.origin.orientation.y, taken.info.origin.orientation.w) == (0.1, 0.97)
        and taken.data.tolist() == list(sample.data)
    )
    return lean if ok else None


def lean_goal_request_type(action: Any) -> Any | None:
    """``action``'s goal request class (a FollowPath) whose taken requests are :class:`LeanGoalRequest`; None when
    the layout check fails."""
    from rclpy.serialization import deserialize_message, serialize_message

    real = action.Impl.SendGoalService.Request
    lean = _lean_class(real, "LeanFollowPathGoalRequest", _goal_request_from_c)
    sample = real()
    sample.goal_id.uuid = np.arange(3, 19, dtype=np.uint8)
    _sample_path(sample.goal.path)
    taken = deserialize_message(serialize_message(sample), lean)
    ok = (
        isinstance(taken, LeanGoalRequest)
        and bytes(taken.goal_id.uuid) == bytes(sample.goal_id.uuid)
        and _same(taken.goal.path, PathArrays.of(sample.goal.path))
    )
    return lean if ok else None


def lean_action_server_class() -> Any:
    """rclpy's ``ActionServer`` that takes goal requests as its ``lean_request`` class (when set), the rest as
    rclpy does (made once rclpy is imported)."""
    from rclpy.action import ActionServer

    class LeanGoalActionServer(ActionServer):
        lean_request: Any = None

        def take_data(self):
            goal = None
            if self.lean_request is not None and getattr(self, "_is_goal_request_ready", False):
                with self._lock:
                    taken = self._handle.take_goal_request(self.lean_request)
                if taken[0]:
                    goal = taken
                self._is_goal_request_ready = False  # taken here: rclpy's own take below leaves it
            data = super().take_data()
            if goal is not None:
                data["goal"] = goal
            return data

    return LeanGoalActionServer


def _librcl() -> Any:
    """rcl's shared library as loaded by rclpy (the same file: ``dlopen`` returns the loaded one)."""
    with open("/proc/self/maps") as maps:
        for line in maps:
            path = line.split()[-1]
            if re.search(r"/librcl(-[0-9a-f]{8})?\.so", path):
                return ctypes.CDLL(path)
    raise OSError("librcl is not loaded")


def _capsule_pointer(capsule: Any) -> int:
    get = ctypes.pythonapi.PyCapsule_GetPointer
    get.restype, get.argtypes = ctypes.c_void_p, [ctypes.py_object, ctypes.c_char_p]
    name = ctypes.pythonapi.PyCapsule_GetName
    name.restype, name.argtypes = ctypes.c_char_p, [ctypes.py_object]
    return int(get(capsule, name(capsule)))


RCL_RET_OK = 0
TAKE_PERIOD_S = 0.1


class TakenAside:
    """A subscription to ``topic`` taken by a thread of its own, ``rcl_take`` called without the GIL; each message
    ``read(address of the C message)`` (which must copy what it keeps) and handed to ``callback``; what the callback
    raises goes to ``on_error`` (a text) and the thread goes on."""

    def __init__(self, node: Any, msg_type: Any, topic: str, qos: Any, read, callback, on_error=print) -> None:
        import threading

        from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
        from rclpy.type_support import check_is_valid_msg_type

        check_is_valid_msg_type(msg_type)
        rcl = _librcl()
        self._take = rcl.rcl_take
        self._take.restype = ctypes.c_int
        self._take.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p]
        self._create = ctypes.CFUNCTYPE(ctypes.c_void_p)(_capsule_pointer(msg_type._CREATE_ROS_MESSAGE))
        self._destroy = ctypes.CFUNCTYPE(None, ctypes.c_void_p)(_capsule_pointer(msg_type._DESTROY_ROS_MESSAGE))
        with node.handle:
            self._subscription = _rclpy.Subscription(node.handle, msg_type, topic, qos.get_c_qos_profile())
        self._read, self._callback, self._on_error = read, callback, on_error
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name=f"viapath-take-{topic}", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        info = ctypes.create_string_buffer(4096)  # rmw_message_info_t (a few hundred bytes)
        pointer = self._subscription.pointer
        while not self._stop.wait(TAKE_PERIOD_S):
            while not self._stop.is_set():
                message = self._create()
                if not message:
                    break
                try:
                    if self._take(pointer, message, ctypes.cast(info, ctypes.c_void_p), None) != RCL_RET_OK:
                        break  # nothing waiting (or a failure rcl reports on the next take too)
                    value = self._read(message)
                finally:
                    self._destroy(message)  # frees the C message's memory, without the GIL
                try:
                    self._callback(value)
                except Exception as error:  # said, and the thread goes on with the next message
                    self._on_error(f"{type(error).__name__}: {error}")

    def destroy(self) -> None:
        self._stop.set()
        self._thread.join(timeout=5.0)
        self._subscription.destroy_when_not_in_use()
