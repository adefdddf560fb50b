"""``viapath ros2 node``: the planner as a ROS 2 (lifecycle) node.

Source: docs/design.md §8 (topics, QoS, parameters from the option schema, ``use_sim_time``); the ROS 2
managed-node design (configure / activate / deactivate / cleanup, ``rclpy.lifecycle``). All the
decisions of a cycle are in :class:`viapath.ros2.core.PlannerCore`; this module converts messages
and owns the timers.

What we chose:
* Lifecycle: parameters are declared at construction; ``configure`` validates them (a bad value is
  refused with a message naming the parameter: the transition fails and the node never drives),
  builds the core and the publishers and subscriptions; ``activate`` starts commanding;
  ``deactivate`` publishes a zero command first. With ``autostart`` (default) the node configures
  and activates itself; ``viapath ros2 node`` exits with code 2 when configuring fails.
* Scans arrive with the sensor-data QoS (best effort, depth 5); odometry reliable depth 10; the
  path is subscribed transient-local (a latched path published before the node started is received).
* ``cmd_vel`` is published once per scan cycle and, when inputs are stale and no scan cycle ran for 1.5
  periods, by the watchdog (every ``cycle_period_s``): one command per period; markers and the DiagnosticArray (``status_topic``) once per cycle. The same array goes
  to ``diagnostics_topic`` (``/diagnostics``, where robot monitors and ``diagnostic_aggregator`` look) once a
  second, and at once when the way's state changes (``blocked``: static geometry closes it, level WARN).
* Paths and maps are decoded, checked, simplified and rasterised by a worker thread
  (:mod:`viapath.ros2.background`), never in a callback of the control loop: the cycles go on with
  the last good path and map and take the new one at the first cycle after it is ready, so ``cmd_vel``
  keeps its rate whatever the size of what arrives.
* The map is subscribed by a node in a ROS context of its own, so a DDS participant of its own (its own
  receive buffers and threads): a 10 000 x 10 000 map is 100 MB, thousands of fragments, and through the
  control loop's participant they crowded out scans sent meanwhile (best effort: lost, the cycle missed,
  0.2 s without ``cmd_vel``; 2 scan pairs of 10 maps on one run, none with the participant of its own). Its
  topic is resolved by the node (namespace and remappings) first.
* Every node of the process has a name of its own, the node's resolved name with a suffix, in its namespace
  (``<name>_inputs``, ``<name>_map``), and takes no global arguments: a ``-r __node:=controller_server`` (how
  Nav2 starts its controller) applies to the node alone, never two nodes of one name in the graph (rclpy's
  "already registered" warning on /rosout, parameter and lifecycle tools confused). The topic and action
  names of the other nodes are resolved by the node, so the user's remappings reach them all the same.
* Signals: SIGINT / SIGTERM end the spin loop; a zero command is published before the node is
  destroyed (rclpy's own handlers would shut the context down before we could publish).
"""

from __future__ import annotations

import functools
import math
import signal
import sys
import threading
import time
from typing import Any

from viapath.ros2 import convert
from viapath.ros2.core import CycleResult, PlannerCore, severity
from viapath.ros2.settings import NODE_NAME, ParameterError, all_options, describe, validate

DIAGNOSTICS_PERIOD_S = 1.0  # on diagnostics_topic, as ROS's diagnostic_updater publishes


def locked(method):
    """The node's callback under the node's lock: the control loop's callbacks and those of the input
    thread (goals) change the same state."""

    @functools.wraps(method)
    def run(self, *args, **kwargs):
        with self.lock:
            return method(self, *args, **kwargs)

    return run


def _parameter_descriptor(option, read_only: bool = True):
    """Description with unit and bounds. Typing is dynamic: ``validate`` converts and checks every
    value with a message naming the parameter (rclpy's own checks would refuse ``1`` for a double)."""
    from rcl_interfaces.msg import ParameterDescriptor

    d = ParameterDescriptor()
    d.description = describe(option)
    d.read_only = read_only
    d.dynamic_typing = True
    return d


def _declare_all(node, planner_name: str, scanner_names) -> dict[str, Any]:
    """Declare every parameter (defaults from the schema) and return the values the node was given."""
    from rclpy.exceptions import ParameterAlreadyDeclaredException

    values: dict[str, Any] = {}
    for option in all_options(planner_name, scanner_names):
        default = option.default
        if isinstance(default, tuple):
            default = list(default)
        if (
            isinstance(default, list)
            and default
            and isinstance(default[0], (int, float))
            and not isinstance(default[0], bool)
        ):
            default = [float(v) for v in default]
        try:
            node.declare_parameter(option.name, default, _parameter_descriptor(option), ignore_override=False)
        except ParameterAlreadyDeclaredException:
            pass
        except Exception as error:  # a given value of the wrong type: name the parameter
            raise ParameterError(f"parameter {option.name}: {error}") from None
        value = node.get_parameter(option.name).value
        if isinstance(value, (tuple,)) or type(value).__name__ == "array":
            value = list(value)
        values[option.name] = value
    return values


_LifecycleNode: Any = object  # rclpy's LifecycleNode, joined in make_node_class (typed as Any here)


class _NodeBehaviour(_LifecycleNode):
    """What :class:`ViaPathNode` does (scans + odometry + designated path in; cmd_vel, markers and
    diagnostics out), kept apart from rclpy's ``LifecycleNode`` so that importing this module needs no
    rclpy: :func:`make_node_class` joins the two. The message types are imported where they are used."""

    nav2_interface_class: Any = None  # set by make_node_class

    def __init__(self, node_name: str = NODE_NAME, **kwargs):
        super().__init__(node_name, **kwargs)
        self.error: str | None = None
        self.core: Any = None  # a PlannerCore once configured
        self._subs: list = []
        self._pubs: dict[str, Any] = {}
        self._timer = None
        self._nav2 = None
        self._wall_timer = None
        self._last_now_s: float | None = None
        self._diagnostics_sent: tuple[float, str] | None = None  # (wall time, the way's state) last sent there
        from viapath.ros2.background import Background

        self.background = Background()
        self.lock = threading.RLock()
        self.inputs_node: Any = None  # a second node, spun in a thread of its own: big inputs (see below)
        self._inputs_thread: threading.Thread | None = None
        self._inputs_running = False
        self._input_subs: list = []
        self._takers: list = []  # subscriptions taken by threads of their own (viapath.ros2.lean.TakenAside)
        self._map_node: Any = None  # the map's node, in a context (a DDS participant) of its own (see below)
        try:
            self.declare_parameter("planner_name", "viapath")
            self.declare_parameter("scanner_names", ["front", "rear"])
            planner_name = self.get_parameter("planner_name").value
            scanner_names = list(self.get_parameter("scanner_names").value)
            from viapath.planning import available_planners

            if planner_name not in available_planners():
                raise ParameterError(
                    f"parameter planner_name: unknown planner {planner_name!r}; available: "
                    f"{', '.join(available_planners())}"
                )
            self.given = _declare_all(self, planner_name, scanner_names)
        except ParameterError as error:
            self.error = str(error)
            self.given = {}

    # -- lifecycle -----------------------------------------------------------------------
    def on_configure(self, state):
        from rclpy.lifecycle import TransitionCallbackReturn

        if self.error is None:
            self._build_core()
        if self.error is not None:
            self.get_logger().error(f"refusing to start: {self.error}")
            return TransitionCallbackReturn.FAILURE
        from viapath.ros2.markers import MarkerScenes

        s = self.core.settings
        self._scenes = MarkerScenes(s.robot_radius_m)
        self._create_publishers(s)
        self._create_input_subscriptions(s)
        if s.interface == "nav2":
            try:
                self._nav2 = self.nav2_interface_class(self)
            except Exception as error:  # interfaces that cannot be generated here: say why, do not drive
                self.error = f"nav2 interface: {error}"
                self.get_logger().error(f"refusing to start: {self.error}")
                self._teardown()
                return TransitionCallbackReturn.FAILURE
        self._create_path_and_map_subscriptions(s)
        self._start_inputs_thread()
        self.core.active = False
        self._create_timers(s)
        self.get_logger().info(
            f"configured: planner {s.planner_name}, scanners "
            f"{', '.join(sc.topic for sc in s.scanners)}, odometry {s.odom_topic}"
        )
        return TransitionCallbackReturn.SUCCESS

    def _build_core(self) -> None:
        """Validate the parameters and build the planner core (and the path of ``path_file``); on a
        failure ``self.error`` says why."""
        try:
            settings = validate(self.given)
            self.core = PlannerCore(settings)
            self.core.warm_up()
            if settings.path_file:
                try:
                    waypoints, widths = convert.load_path_file(settings.path_file)
                    self.core.set_path(waypoints, widths)
                except ValueError as error:
                    raise ParameterError(f"parameter path_file: {error}") from None
        except ParameterError as error:
            self.error = str(error)
        except Exception as error:
            self.error = f"could not build the planner with these parameters: {type(error).__name__}" + (
                f": {error}" if str(error) else ""
            )

    def _create_publishers(self, s) -> None:
        from diagnostic_msgs.msg import DiagnosticArray
        from geometry_msgs.msg import Twist, TwistStamped
        from visualization_msgs.msg import MarkerArray

        cmd_type = TwistStamped if s.cmd_vel_stamped else Twist
        self._pubs["cmd"] = self.create_lifecycle_publisher(cmd_type, s.cmd_vel_topic, 10)
        self._pubs["markers"] = self.create_lifecycle_publisher(MarkerArray, s.markers_topic, 5)
        self._pubs["status"] = self.create_lifecycle_publisher(DiagnosticArray, s.status_topic, 10)
        if s.diagnostics_topic:
            self._pubs["diagnostics"] = self.create_lifecycle_publisher(DiagnosticArray, s.diagnostics_topic, 10)

    def _create_input_subscriptions(self, s) -> None:
        from nav_msgs.msg import Odometry
        from rclpy.qos import QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
        from rosgraph_msgs.msg import Clock
        from sensor_msgs.msg import LaserScan

        # Odometry first: when odometry and scans are both waiting, the executor takes odometry first.
        self._subs.append(self.create_subscription(Odometry, s.odom_topic, self._on_odom, 10))
        for index, scanner in enumerate(s.scanners):
            self._subs.append(
                self.create_subscription(
                    LaserScan, scanner.topic, lambda msg, i=index: self._on_scan(i, msg), qos_profile_sensor_data
                )
            )
        if self.get_parameter("use_sim_time").value:  # a /clock message is a sign of life, moving or not
            self._subs.append(
                self.create_subscription(
                    Clock,
                    "/clock",
                    lambda msg: self.core.note_alive(time.monotonic()),
                    QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT),
                )
            )

    @property
    def inputs(self):
        """The node that takes the inputs whose size has no bound (paths, maps, FollowPath goals): rclpy turns
        a message into Python objects in the thread that takes it (seconds for 100 000 poses), so they are
        taken by a second node spun in a thread of its own, never by the control loop's executor.

        It is named after the node (``<name>_inputs`` in its namespace) and takes no global arguments: with
        them, a ``-r __node:=NAME`` (how Nav2 starts its controller) would give it the node's name, two nodes
        of one name in the graph. So its topic and action names are resolved by the node first
        (:meth:`resolve_input_name`): the user's remappings and namespace apply as they do to the node."""
        if self.inputs_node is None:
            from rclpy.node import Node
            from rclpy.parameter import Parameter

            self.inputs_node = Node(
                f"{self.get_name()}_inputs",
                namespace=self.get_namespace(),
                context=self.context,
                start_parameter_services=False,
                use_global_arguments=False,
                parameter_overrides=[
                    Parameter("use_sim_time", Parameter.Type.BOOL, bool(self.get_parameter("use_sim_time").value))
                ],
            )
        return self.inputs_node

    def resolve_input_name(self, name: str) -> str:
        """``name`` (a topic or action) as the node resolves it: namespace, ``~`` and remappings applied, for
        the nodes that take no global arguments (the inputs' and the map's)."""
        return self.resolve_topic_name(name)

    def _start_inputs_thread(self) -> None:
        if self.inputs_node is None or self._inputs_thread is not None:
            return
        from rclpy.executors import SingleThreadedExecutor

        executor = SingleThreadedExecutor(context=self.context)
        executor.add_node(self.inputs_node)
        self._inputs_running = True

        def spin() -> None:
            while self._inputs_running and self.context.ok():
                try:
                    executor.spin_once(timeout_sec=0.05)
                except Exception as error:  # an input that cannot be taken: said, and the thread goes on
                    if self._inputs_running:
                        self.get_logger().error(f"input thread: {type(error).__name__}: {error}")
            executor.remove_node(self.inputs_node)
            executor.shutdown(timeout_sec=0.0)

        self._inputs_thread = threading.Thread(target=spin, name="viapath-inputs", daemon=True)
        self._inputs_thread.start()

    def destroy_node(self) -> None:
        """The input thread stops (and its node goes) before the node itself."""
        self._stop_inputs_thread_only()
        self._destroy_inputs_node()
        super().destroy_node()  # LifecycleNode's, next in the node class's MRO

    def _stop_inputs_thread_only(self) -> None:
        thread, self._inputs_thread = self._inputs_thread, None
        self._inputs_running = False
        if thread is not None:
            thread.join(timeout=5.0)

    def _destroy_inputs_node(self) -> None:
        for taker in self._takers:
            taker.destroy()
        self._takers = []
        if self._map_node is not None:
            map_node, self._map_node = self._map_node, None
            map_node.destroy_node()
            map_node.context.try_shutdown()
        if self.inputs_node is not None:
            for sub in self._input_subs:
                self.inputs_node.destroy_subscription(sub)
            self._input_subs = []
            self.inputs_node.destroy_node()
            self.inputs_node = None

    def _create_path_and_map_subscriptions(self, s) -> None:
        from nav_msgs.msg import Path as PathMsg
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

        from viapath.ros2.lean import lean_path_type

        latched = QoSProfile(
            depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
        )
        if s.interface != "nav2" and not s.path_file:
            path_type = PathMsg
            try:  # taken as arrays: no Python object per pose (viapath.ros2.lean)
                path_type = lean_path_type() or PathMsg
            except Exception as error:
                self.get_logger().warning(f"paths taken as Python messages: {type(error).__name__}: {error}")
            if path_type is PathMsg:
                self.get_logger().warning("paths taken as Python messages (slow for long paths)")
            self._input_subs.append(
                self.inputs.create_subscription(
                    path_type, self.resolve_input_name(s.path_topic), self._on_path, latched
                )
            )
        if s.map_topic:
            from nav_msgs.msg import OccupancyGrid

            from viapath.ros2.lean import TakenAside, grid_from_c, lean_grid_type

            try:  # taken and copied without the GIL by a thread of its own (viapath.ros2.lean)
                if lean_grid_type() is None:
                    raise TypeError("unknown message layout")
                self._takers.append(
                    TakenAside(
                        self._map_participant(),
                        OccupancyGrid,
                        self.resolve_input_name(s.map_topic),
                        latched,
                        grid_from_c,
                        self._on_map,
                        on_error=lambda text: self.get_logger().error(f"map: {text}"),
                    )
                )
            except Exception as error:  # the ordinary subscription then: the GIL held while a big map is taken
                self.get_logger().warning(f"maps taken by rclpy: {type(error).__name__}: {error}")
                self._input_subs.append(
                    self.inputs.create_subscription(
                        OccupancyGrid, self.resolve_input_name(s.map_topic), self._on_map, latched
                    )
                )

    def _map_participant(self):
        """A node for the map in a context of its own, so a DDS participant of its own: its own receive
        buffers and threads. A map of 100 MB arrives as thousands of fragments; into the control loop's
        participant they crowd out the scans (best effort, so lost: a cycle missed) while they arrive."""
        import rclpy
        from rclpy.node import Node

        context = rclpy.Context()
        context.init(args=[], initialize_logging=False, domain_id=self.context.get_domain_id())
        try:
            self._map_node = Node(
                f"{self.get_name()}_map",
                namespace=self.get_namespace(),
                context=context,
                start_parameter_services=False,
                enable_rosout=False,
                use_global_arguments=False,
            )
        except Exception:
            context.try_shutdown()
            raise
        return self._map_node

    def _create_timers(self, s) -> None:
        from rclpy.clock import Clock as RosClock
        from rclpy.clock import ClockType

        self._timer = self.create_timer(s.cycle_period_s, self._on_watchdog)
        # The same period on the wall clock: with use_sim_time the timer above stops with /clock.
        self._wall_timer = self.create_timer(
            s.cycle_period_s, self._on_wall_watchdog, clock=RosClock(clock_type=ClockType.STEADY_TIME)
        )

    def on_activate(self, state):
        result = super().on_activate(state)
        self.core.active = True
        self.get_logger().info("active: commanding " + self.core.settings.cmd_vel_topic)
        return result

    def on_deactivate(self, state):
        self.publish_stop()
        self.core.active = False
        if self._nav2 is not None:
            self._nav2.deactivated()
        return super().on_deactivate(state)

    def on_cleanup(self, state):
        from rclpy.lifecycle import TransitionCallbackReturn

        self._teardown()
        return TransitionCallbackReturn.SUCCESS

    def on_shutdown(self, state):
        from rclpy.lifecycle import TransitionCallbackReturn

        self.publish_stop()
        self._teardown()
        return TransitionCallbackReturn.SUCCESS

    def _teardown(self) -> None:
        for kind in ("path", "map", "goal"):
            self.background.cancel(kind)
        if self._nav2 is not None:
            self._nav2.end_goal()
            until = time.monotonic() + 2.0  # the goal's result goes out from the input thread
            while self._nav2.results_pending and self._inputs_thread is not None and time.monotonic() < until:
                time.sleep(0.01)
            until = time.monotonic() + 0.2  # and the result to the client that asked for it
            while time.monotonic() < until:
                time.sleep(0.01)
        self._stop_inputs_thread_only()
        if self._nav2 is not None:
            self._nav2.destroy()
            self._nav2 = None
        self._destroy_inputs_node()
        for timer in (self._timer, self._wall_timer):
            if timer is not None:
                self.destroy_timer(timer)
        self._timer = self._wall_timer = None
        for sub in self._subs:
            self.destroy_subscription(sub)
        self._subs = []
        for pub in self._pubs.values():
            self.destroy_lifecycle_publisher(pub)
        self._pubs = {}

    # -- time ----------------------------------------------------------------------------
    def _now_s(self, alive: bool = True) -> float:
        """The node's clock; ``alive``: an input arrived now (for the wall-clock watchdog)."""
        now = self.get_clock().now().nanoseconds * 1e-9
        if self._last_now_s is not None and now < self._last_now_s - 1e-9 and self.core is not None:
            self.core.clock_jumped_back(f"the node's clock went back {self._last_now_s - now:.3f} s")
        if self.core is not None and (alive or self._last_now_s is None or now != self._last_now_s):
            self.core.note_alive(time.monotonic())
        self._last_now_s = now
        return now

    # -- inputs --------------------------------------------------------------------------
    def _failed(self, what: str, error: Exception) -> str:
        text = f"{what} failed: {type(error).__name__}: {error}"
        self.get_logger().error(text)
        return text

    @locked
    def _on_odom(self, msg) -> None:
        try:
            x, y, q, v, w = convert.odometry_values(msg)
            self.core.on_odometry_quaternion(
                self._now_s(), convert.stamp_seconds(msg.header.stamp), msg.header.frame_id, x, y, q, v, w
            )
        except Exception as error:
            self.core.refuse_odometry(self._now_s(), "error", self._failed("reading odometry", error))

    @locked
    def _on_map(self, msg) -> None:
        if getattr(msg, "error", ""):
            self._map_refused(f"its cells could not be read ({msg.error})")
            return
        expected = self.core.settings.odom_frame
        if expected and msg.header.frame_id != expected:  # an empty frame_id says nothing of where the map is
            self._map_refused(f"frame_id {msg.header.frame_id!r}, expected {expected!r}")
            return
        core, threshold = self.core, self.core.settings.map_occupied_threshold
        self.background.submit("map", lambda: core.prepare_map(convert.occupancy_layer_from_message(msg, threshold)))

    def _map_refused(self, why: str) -> None:
        self.core.events.append(f"map refused: {why} (the last good map stays)")
        self.get_logger().error(self.core.events[-1])

    @locked
    def _on_path(self, msg) -> None:
        from viapath.ros2.lean import PathArrays

        core = self.core

        def prepare():
            path = PathArrays.of(msg)  # a Python message (no lean type here) read in the worker
            if path.error:
                return "refused", f"its poses could not be read ({path.error})"
            return core.prepare_path_message(path.frame_id, path.positions, path.orientations)

        self.background.submit("path", prepare)

    def take_background(self) -> None:
        """Use the paths and maps the worker has finished (at the start of each cycle and watchdog tick)."""
        outcome = self.background.take("map")
        if outcome is not None:
            if outcome.error is not None:
                self._map_refused(str(outcome.error))
            else:
                self.core.set_map(outcome.value)
                self.get_logger().info(self.core.events[-1])
        outcome = self.background.take("path")
        if outcome is not None:
            if outcome.error is not None:
                self.core.paths_refused += 1
                accepted, what = False, self._failed("path refused: reading it", outcome.error)
                self.core.events.append(what)
            else:
                accepted, what = self.core.use_path_message(outcome.value)
            (self.get_logger().info if accepted else self.get_logger().error)(what)
        if self._nav2 is not None:
            self._nav2.take_background()

    @locked
    def _on_scan(self, index: int, msg) -> None:
        due = self.core.on_scan(
            index,
            self._now_s(),
            convert.stamp_seconds(msg.header.stamp),
            msg.header.frame_id,
            msg.angle_min,
            msg.angle_increment,
            msg.ranges,
            msg.range_min,
            msg.range_max,
        )
        if self._nav2 is not None and not self._nav2.mounts_done:
            self._nav2.resolve_mounts()
        if due:
            self.take_background()
            now = self._now_s()
            try:
                result = self.core.cycle(now)
            except Exception as error:
                result = self.core.fault_result(now, self._failed("cycle", error))
            self._publish(result)
            if self._nav2 is not None:
                self._nav2.supervise(result, self._now_s())

    @locked
    def _on_watchdog(self) -> None:
        if self.core is None:
            return
        self.take_background()
        result = self.core.watchdog(self._now_s(alive=False))
        if result is not None:
            self._publish(result, markers=False)

    @locked
    def _on_wall_watchdog(self) -> None:
        if self.core is None:
            return
        self._now_s(alive=False)  # the node's clock moving counts as alive
        result = self.core.wall_watchdog(time.monotonic())
        if result is not None:
            self._publish(result, markers=False)
        if self._nav2 is not None:
            self._nav2.supervise(result, self._now_s())

    # -- outputs -------------------------------------------------------------------------
    def _stamp(self, seconds: float):
        return convert.time_msg(seconds)

    def _command_msg(self, v: float, w: float, stamp_s: float):
        from geometry_msgs.msg import Twist, TwistStamped

        twist = Twist()
        twist.linear.x, twist.angular.z = float(v), float(w)
        if not self.core.settings.cmd_vel_stamped:
            return twist
        msg = TwistStamped()
        msg.header.stamp = self._stamp(stamp_s)
        msg.header.frame_id = self.core.settings.base_frame
        msg.twist = twist
        return msg

    def _publish(self, result: CycleResult, markers: bool = True) -> None:
        if not self.core.active:
            return
        cmd = result.command
        assert math.isfinite(cmd.speed_mps) and math.isfinite(cmd.turn_rate_radps)
        self._pubs["cmd"].publish(self._command_msg(cmd.speed_mps, cmd.turn_rate_radps, result.stamp_s))
        stamp = self._stamp(result.stamp_s)
        path = self.core.path
        if markers and path is not None and self._pubs["markers"].get_subscription_count() > 0:
            # built only for someone watching, after cmd_vel is out
            from viapath.ros2.markers import marker_array

            scene = self._scenes.scene(path, self.core.planner, result)
            corridor = self._scenes.builder(path, self.core.planner).path_view
            self._pubs["markers"].publish(marker_array(scene, corridor, self.core.settings.odom_frame or "odom", stamp))
        diagnostics = self._diagnostics(result, stamp)
        self._pubs["status"].publish(diagnostics)
        if "diagnostics" in self._pubs:  # a robot monitor's rate, and a change of the way at once
            way, sent, now = result.status.get("way", {}).get("state", ""), self._diagnostics_sent, time.monotonic()
            if sent is None or sent[1] != way or now - sent[0] >= DIAGNOSTICS_PERIOD_S:
                self._pubs["diagnostics"].publish(diagnostics)
                self._diagnostics_sent = (now, way)

    def _inputs_matched(self) -> bool:
        """Whether every input topic has a publisher (the simulator waits for this before its first step)."""
        s = self.core.settings
        topics = [sc.topic for sc in s.scanners] + [s.odom_topic]
        return all(self.count_publishers(t) > 0 for t in topics)

    def _diagnostics(self, result: CycleResult, stamp):
        from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

        if result.cycle_time_ms is None:  # watchdog ticks only: cheap enough there
            result.status["planner"]["inputs_matched"] = str(int(self._inputs_matched()))
        out = DiagnosticArray()
        out.header.stamp = stamp
        level_of = {0: DiagnosticStatus.OK, 1: DiagnosticStatus.WARN, 2: DiagnosticStatus.ERROR}
        for name, values in result.status.items():
            status = DiagnosticStatus()
            status.name = f"{self.get_name()}: {name}"
            status.hardware_id = self.get_name()
            if name == "planner":
                status.level = level_of[severity(result)]
                status.message = result.mode + (f" ({'; '.join(result.reasons)})" if result.reasons else "")
            else:
                ok = values.get("state", "ok") == "ok"
                status.level = DiagnosticStatus.OK if ok else DiagnosticStatus.WARN
                status.message = values.get("message", values.get("state", ""))
            status.values = [KeyValue(key=str(k), value=str(v)) for k, v in values.items()]
            out.status.append(status)
        return out

    def publish_stop(self) -> None:
        if self.core is None or "cmd" not in self._pubs:
            return
        self.core.stop_command()
        now = self._now_s(alive=False)
        for _ in range(3):  # best effort against a lossy link; the subscriber's depth keeps them
            try:
                self._pubs["cmd"].publish(self._command_msg(0.0, 0.0, now))
            except Exception:  # the context may already be going down
                break


def make_node_class():
    """The node class (built lazily: importing this module must not need rclpy)."""
    from rclpy.lifecycle import LifecycleNode

    from viapath.ros2.nav2 import make_nav2_interface_class

    class ViaPathNode(_NodeBehaviour, LifecycleNode):
        """Scans + odometry + designated path in; cmd_vel, markers and diagnostics out."""

    ViaPathNode.nav2_interface_class = make_nav2_interface_class()
    return ViaPathNode


def _executor(kind: str):
    """rclpy's EventsExecutor where it exists (Kilted: ``rclpy.experimental``), which takes a callback
    from DDS to Python without rebuilding a wait set per wake-up (the pure-Python executor's cost,
    about a millisecond per scan on this machine); else, or when asked, the SingleThreadedExecutor."""
    from rclpy.executors import SingleThreadedExecutor

    if kind == "events":
        try:
            from rclpy.experimental import EventsExecutor
        except ImportError:
            return SingleThreadedExecutor()
        return EventsExecutor()
    return SingleThreadedExecutor()


def run_node(ros_args: list[str] | None = None) -> int:
    """Start the node (``ros_args``: arguments after ``--ros-args``); returns the exit code."""
    import rclpy
    from rclpy.signals import SignalHandlerOptions

    args = [sys.argv[0]] + (["--ros-args", *ros_args] if ros_args else [])
    rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    stop = {"flag": False}

    def _handler(signum, frame):
        stop["flag"] = True

    previous = {s: signal.signal(s, _handler) for s in (signal.SIGINT, signal.SIGTERM)}
    node = None
    try:
        node = make_node_class()()
        if node.error is not None:
            print(f"error: {node.error}", file=sys.stderr)
            return 2
        autostart = bool(node.get_parameter("autostart").value)
        if autostart:
            from rclpy.lifecycle import TransitionCallbackReturn

            if node.trigger_configure() != TransitionCallbackReturn.SUCCESS:
                print(f"error: {node.error or 'configuring the node failed (see the log above)'}", file=sys.stderr)
                return 2
            node.trigger_activate()
        executor = _executor(str(node.get_parameter("executor").value))
        executor.add_node(node)
        while not stop["flag"] and rclpy.ok():
            executor.spin_once(timeout_sec=0.05)
        return 0
    finally:
        if node is not None:
            node.publish_stop()
            node.destroy_node()
        for s, h in previous.items():
            signal.signal(s, h)
        if rclpy.ok():
            rclpy.shutdown()
