"""Hostile inputs to the node's cycle logic (no rclpy): odometry that lies, malformed scans, bad
quaternions, empty paths, a stopped clock. Each class is tried with generated cases, not one example.

The robot here is an honest base: it drives exactly the commanded (v, w) for a cycle; scans are
ray-cast at its true pose. What the odometry reports is that truth changed by the lie under test.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from viapath.observation import Command
from viapath.perception.raycast import simulate_scan
from viapath.perception.scanner import ScannerModel
from viapath.ros2.core import Odometry, PlannerCore
from viapath.ros2.settings import validate

SCANNERS = (ScannerModel.urg04lx("front", "forward"), ScannerModel.urg04lx("rear", "backward"))
FRAMES = ("laser_front", "laser_rear")
DT = 0.1
STEP = 0.8 * DT  # one cycle's braking at the default max_accel_mps2
EPS = 1e-9
FEW = settings(max_examples=12, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck))


def make_core(**values) -> PlannerCore:
    core = PlannerCore(validate(values))
    core.set_path([[0.0, 0.0], [8.0, 0.0]])
    return core


class Robot:
    """An honest base that drives the commanded (v, w) for one cycle, and the scans it sees."""

    def __init__(self, people=((3.0, 0.0),), speed=0.0):
        self.x = self.y = self.heading = 0.0
        self.v, self.w = speed, 0.0
        self.people = np.array(people, dtype=float).reshape(-1, 2)

    def drive(self, command: Command) -> None:
        self.v, self.w = command.speed_mps, command.turn_rate_radps
        mid = self.heading + 0.5 * self.w * DT
        self.x += self.v * DT * math.cos(mid)
        self.y += self.v * DT * math.sin(mid)
        self.heading += self.w * DT

    def scans(self):
        pose = np.array([self.x, self.y, self.heading])
        return [simulate_scan(s, pose, self.people, np.full(len(self.people), 0.25)) for s in SCANNERS]


def cycle(core, robot, t, odom=None):
    """One cycle: odometry (the truth, or ``odom`` = (x, y, heading, v, w)), both scans, the plan; the robot drives."""
    x, y, h, v, w = odom if odom is not None else (robot.x, robot.y, robot.heading, robot.v, robot.w)
    core.on_odometry(t, t, "odom", x, y, h, v, w)
    for i, (s, ranges) in enumerate(zip(SCANNERS, robot.scans(), strict=True)):
        core.on_scan(i, t, t, FRAMES[i], s.angle_min_rad, s.angle_increment_rad, ranges)
    before = core.last_command
    result = core.cycle(t)
    robot.drive(result.command)
    return result, before


def drive_honestly(core, robot, cycles, t0=1.0):
    t = t0
    for _ in range(cycles):
        cycle(core, robot, t)
        t += DT
    return t


def assert_braking(result, before):
    """Never faster than one cycle's braking from the last command; turning no faster either."""
    assert result.command.speed_mps <= max(0.0, before.speed_mps - STEP) + EPS, (result.command, before, result.reasons)
    assert abs(result.command.turn_rate_radps) <= abs(before.turn_rate_radps) + EPS


# -- 1. odometry that lies ------------------------------------------------------------------------


@pytest.mark.parametrize("twist", [1e9, 40.0, 0.6])
def test_lying_odometry_never_moves_a_standing_robot_towards_a_person(twist):
    """A person 0.3 m ahead of the body, the robot stands; the odometry's twist says it drives."""
    core = make_core()
    robot = Robot(people=[(0.25 + 0.3 + 0.25, 0.0)])
    t = drive_honestly(core, robot, 8)  # it creeps while the track confirms, then the planner stops it
    assert robot.v == 0.0
    x = robot.x
    for k in range(15):
        result, _before = cycle(core, robot, t, odom=(x, 0.0, 0.0, twist, 0.0))
        assert result.command.speed_mps == 0.0, (k, result.command, result.reasons)
        t += DT
    assert robot.x == x
    assert "odometry fault" in result.status["planner"]["reasons"]
    assert result.status["odometry"]["state"] == "fault" and result.status["odometry"]["last_problem"]


@settings(max_examples=200, deadline=None, derandomize=True)
@given(
    measured=st.floats(-1.0, 0.7),
    measured_turn=st.floats(-2.3, 2.3),
    last=st.floats(0.0, 0.6),
    last_turn=st.floats(-2.0, 2.0),
    wanted_turn=st.floats(-2.0, 2.0),
)
def test_a_planner_stop_is_never_turned_into_motion_by_the_ramp(measured, measured_turn, last, last_turn, wanted_turn):
    """Whatever the (accepted) odometry says, a stop asked for by the planner is at least one cycle's
    braking from the last command, and braking never speeds up or turns faster than commanded."""
    core = make_core()
    core.odometry = Odometry(1.0, 1.0, 0.0, 0.0, 0.0, measured, measured_turn)
    core._now_s = 1.0
    core.last_command, core.last_command_s = Command(last, last_turn), 0.95
    stop = core._limit(Command(0.0, wanted_turn))
    assert stop.speed_mps <= max(0.0, last - STEP) + EPS
    brake = core.brake_command()
    assert brake.speed_mps <= max(0.0, last - STEP) + EPS
    assert abs(brake.turn_rate_radps) <= max(0.0, min(abs(last_turn), abs(measured_turn)) - 6.0 * DT) + EPS or (
        last_turn * measured_turn <= 0 and brake.turn_rate_radps == 0.0
    )


@settings(FEW, max_examples=40)
@given(
    kind=st.sampled_from(["fast", "negative", "stuck", "turn", "spin-stuck", "jump", "heading"]),
    size=st.floats(0.0, 1.0),
    cycles=st.integers(3, 8),
    speed=st.floats(0.1, 0.5),
)
def test_generated_lying_odometry_brakes_and_says_why(kind, size, cycles, speed):
    core = make_core(nominal_speed_mps=speed)
    robot = Robot(people=[(6.0, 1.5)])
    t = drive_honestly(core, robot, cycles)
    lim = core.limits
    for k in range(6):
        truth = (robot.x, robot.y, robot.heading, robot.v, robot.w)
        if kind == "fast":  # beyond the speed limit: a little, or absurdly
            lie = (*truth[:3], lim.max_speed_mps + 0.11 + 10 ** (12 * size), truth[4])
        elif kind == "negative":
            lie = (*truth[:3], -(lim.max_speed_mps + 0.11 + 10 ** (12 * size)), truth[4])
        elif kind == "stuck":  # the twist says more than was commanded, the pose agrees with the truth
            lie = (*truth[:3], min(robot.v + 0.15 + size, lim.max_speed_mps + 0.1), truth[4])
        elif kind == "turn":
            lie = (*truth[:4], math.copysign(lim.max_turn_rate_radps + 0.31 + 100 * size, size - 0.5))
        elif kind == "spin-stuck":  # a turn rate never commanded, inside the limits
            lie = (*truth[:4], robot.w + math.copysign(0.35 + size, size - 0.5))
        elif kind == "jump":  # the pose jumps 0.2 m to 10 km
            a = 2 * math.pi * size
            d = 0.2 * 10 ** (4.7 * size)
            lie = (truth[0] + d * math.cos(a), truth[1] + d * math.sin(a), *truth[2:])
        else:  # heading jumps 0.2 to 3 rad
            lie = (truth[0], truth[1], truth[2] + math.copysign(0.2 + 2.8 * size, size - 0.5), *truth[3:])
        if kind in ("jump", "heading") and k > 0:
            lie = None  # one jump, then the odometry goes on from there (checked below: still braking)
            odom = core.odometry
            lie = (
                odom.x + robot.v * DT * math.cos(odom.heading_rad),
                odom.y + robot.v * DT * math.sin(odom.heading_rad),
                odom.heading_rad,
                robot.v,
                robot.w,
            )
        result, before = cycle(core, robot, t, odom=lie)
        if kind in ("jump", "heading") and k * DT >= core.settings.reset_hold_s - EPS:
            break  # held for reset_hold_s after a jump; then it may go on from the new pose
        assert_braking(result, before)
        assert any("odometry fault" in r for r in result.reasons), result.reasons
        assert not any("('jump'" in r for r in result.reasons), result.reasons  # the text, not a tuple
        t += DT
    assert core.odom_refused and core.odom_problem and isinstance(core.odom_problem, str)
    if kind in ("jump", "heading"):
        assert any("tracks reset" in e for e in core.events)


@FEW
@given(cycles=st.integers(4, 12), speed=st.floats(0.1, 0.6), turn=st.floats(-1.0, 1.0))
def test_honest_odometry_is_never_a_fault(cycles, speed, turn):
    """The checks must not fire on the truth: a base that does what it is told, turning or not."""
    core = make_core(nominal_speed_mps=speed)
    robot = Robot(people=[(5.0, 2.0)], speed=0.0)
    core.set_path([[0.0, 0.0], [3.0, 3.0 * turn], [8.0, -2.0]])
    t = 1.0
    for _ in range(cycles):
        result, _ = cycle(core, robot, t)
        assert not core.odom_refused, core.odom_problem
        assert not any("odometry" in r for r in result.reasons)
        t += DT
    assert robot.v > 0.0


# -- 2. malformed scans, the first one included -----------------------------------------------------


def first_scan(
    core,
    index=0,
    t=1.0,
    beams=683,
    increment=math.radians(0.352),
    range_min=0.02,
    range_max=5.6,
    angle_min=None,
    ranges=None,
):
    ranges = np.full(beams, 2.0) if ranges is None else ranges
    angle_min = -0.5 * (beams - 1) * increment if angle_min is None else angle_min
    return core.on_scan(index, t, t, FRAMES[index], angle_min, increment, ranges, range_min, range_max)


@pytest.mark.parametrize(
    "layout, words",
    [
        ({"range_min": 6.0, "range_max": 1.0}, "not below range_max"),
        ({"beams": 2000, "increment": 0.01}, "more than a full turn"),
        ({"increment": 0.0}, "must be > 0"),
        ({"beams": 1}, "beams"),
        ({"range_max": float("nan")}, "finite"),
        ({"range_min": float("inf")}, "finite"),
    ],
)
def test_a_malformed_first_scan_is_refused_and_the_next_good_one_is_taken(layout, words):
    core = make_core(scan_geometry="from_message")
    assert not first_scan(core, **layout)
    h = core.health[0]
    assert h.model is None and h.refused == {"layout": 1} and words in h.last_problem
    result = core.cycle(1.0)
    assert result.status["scanner front"]["refused"] == "layout: 1"
    assert words in result.status["scanner front"]["last_problem"]
    first_scan(core, t=1.1)  # a good one: the scanner's layout now
    assert h.model is not None and h.good == 1


finite_or_not = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.sampled_from([0.0, -0.0, 1e-300, 1e300]))


@settings(max_examples=60, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck))
@given(
    beams=st.integers(0, 4000),
    increment=finite_or_not,
    range_min=finite_or_not,
    range_max=finite_or_not,
    angle_min=finite_or_not,
    geometry=st.sampled_from(["from_message", "urg04lx"]),
    readings=st.sampled_from(["ok", "nan", "strings", "nested"]),
)
def test_generated_malformed_scans_are_refused_never_raised(
    beams, increment, range_min, range_max, angle_min, geometry, readings
):
    core = make_core(scan_geometry=geometry)
    ranges = {
        "ok": np.full(beams, 2.0),
        "nan": np.full(beams, np.nan),
        "strings": ["x"] * beams,
        "nested": [[1.0, 2.0]] * beams,
    }[readings]
    accepted = core.on_scan(0, 1.0, 1.0, FRAMES[0], angle_min, increment, ranges, range_min, range_max)
    h = core.health[0]
    assert h.good + sum(h.refused.values()) == 1
    if h.good:
        m = h.model
        assert m is not None and m.beam_count >= 2 and m.angle_increment_rad > 0
        assert 0 <= m.range_min_m < m.range_max_m and (m.beam_count - 1) * m.angle_increment_rad <= 2 * math.pi + 1e-6
    else:
        assert not accepted and h.last_problem
    result = core.cycle(1.05)
    c = result.command
    assert math.isfinite(c.speed_mps) and 0.0 <= c.speed_mps <= core.limits.max_speed_mps


# -- 5. quaternions -----------------------------------------------------------------------------------


def test_a_zero_quaternion_is_refused_and_the_robot_does_not_spin():
    core = make_core()
    robot = Robot(people=[(6.0, 2.0)])
    t = drive_honestly(core, robot, 5)
    for _ in range(5):
        core.on_odometry_quaternion(t, t, "odom", robot.x, robot.y, (0.0, 0.0, 0.0, 0.0), robot.v, robot.w)
        for i, (s, ranges) in enumerate(zip(SCANNERS, robot.scans(), strict=True)):
            core.on_scan(i, t, t, FRAMES[i], s.angle_min_rad, s.angle_increment_rad, ranges)
        before = core.last_command
        result = core.cycle(t)
        assert_braking(result, before)
        robot.drive(result.command)
        t += DT
    assert core.odom_refused.get("quaternion") == 5 and "length 0" in core.odom_problem
    assert any("odometry fault: orientation" in r for r in result.reasons)


unit = (
    st.tuples(*[st.floats(-1.0, 1.0)] * 4)
    .filter(lambda q: sum(v * v for v in q) > 1e-3)
    .map(lambda q: tuple(v / math.sqrt(sum(u * u for u in q)) for v in q))
)
anything = st.tuples(*[finite_or_not] * 4)


@settings(max_examples=100, deadline=None, derandomize=True)
@given(
    q=st.one_of(
        unit, anything, unit.map(lambda q: tuple(1.05 * v for v in q)), unit.map(lambda q: tuple(0.5 * v for v in q))
    )
)
def test_generated_quaternions_are_a_heading_only_when_they_are_rotations(q):
    core = make_core()
    with np.errstate(all="ignore"):
        norm = math.sqrt(sum(v * v for v in q)) if all(math.isfinite(v) for v in q) else math.nan
    rotation = math.isfinite(norm) and abs(norm - 1.0) <= 0.01
    accepted = core.on_odometry_quaternion(1.0, 1.0, "odom", 0.0, 0.0, q, 0.0, 0.0)
    assert accepted == rotation
    if rotation:  # the heading is where the rotated x axis points (Hamilton product q (0, 1, 0, 0) q*)
        x, y, z, w = (v / norm for v in q)

        def mul(a, b):
            (ax, ay, az, aw), (bx, by, bz, bw) = a, b
            return (
                aw * bx + ax * bw + ay * bz - az * by,
                aw * by - ax * bz + ay * bw + az * bx,
                aw * bz + ax * by - ay * bx + az * bw,
                aw * bw - ax * bx - ay * by - az * bz,
            )

        axis = mul(mul((x, y, z, w), (1.0, 0.0, 0.0, 0.0)), (-x, -y, -z, w))
        if math.hypot(axis[0], axis[1]) > 1e-6:  # not pointing straight up or down
            error = core.odometry.heading_rad - math.atan2(axis[1], axis[0])
            assert abs(math.atan2(math.sin(error), math.cos(error))) < 1e-6
    else:
        assert core.odom_refused == {"quaternion": 1} and core.odometry_fault_active(1.0)
    # a path with that orientation on one pose
    previous = core.path
    accepted, what = core.on_path("odom", [[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]], [(0, 0, 0, 1), q, (0, 0, 0, 1)])
    assert accepted == rotation
    assert (core.path is not previous) == rotation and (rotation or "pose 1" in what)


# -- 4. paths: empty means stop; bad ones are refused --------------------------------------------------


def test_an_empty_path_stops_the_robot_and_the_status_says_so():
    core = make_core()
    robot = Robot(people=[(6.0, 2.0)])
    t = drive_honestly(core, robot, 6)
    assert robot.v > 0.1
    accepted, what = core.on_path("odom", np.zeros((0, 2)), np.zeros((0, 4)))
    assert accepted and "cleared" in what and core.path is None
    speeds = []
    for _ in range(6):
        result, before = cycle(core, robot, t)
        assert_braking(result, before)
        speeds.append(result.command.speed_mps)
        t += DT
    assert speeds[-1] == 0.0 and result.mode == "stopped"
    assert "designated path cleared by an empty path" in result.status["planner"]["reasons"]
    assert core.on_path("odom", [[robot.x, 0.0], [8.0, 0.0]])[0]  # a new path: it goes again
    for _ in range(4):
        result, _ = cycle(core, robot, t)
        t += DT
    assert result.mode == "driving" and result.command.speed_mps > 0.0


path_points = st.lists(st.tuples(finite_or_not, finite_or_not), min_size=0, max_size=5)


@settings(max_examples=60, deadline=None, derandomize=True)
@given(paths=st.lists(st.tuples(st.sampled_from(["odom", "", "map"]), path_points), min_size=1, max_size=4))
def test_generated_paths_replace_clear_or_leave_the_path(paths):
    core = make_core()
    for frame, points in paths:
        previous = core.path
        accepted, what = core.on_path(frame, np.array(points, dtype=float).reshape(-1, 2))
        assert what
        if not accepted:
            assert core.path is previous and "path refused" in what
        elif not points:
            assert core.path is None and core.path_cleared
        else:
            assert frame in ("odom", "") and np.isfinite(np.array(points)).all()
            assert core.path is not None and core.path is not previous
    result = core.watchdog(1.0)
    assert result is not None and (core.path is not None or any("path" in r for r in result.reasons))


# -- 3. a stopped clock: the watchdog on the wall clock ------------------------------------------------


def test_when_clock_and_inputs_stop_the_wall_watchdog_brakes_to_a_stop():
    core = make_core()
    robot = Robot(people=[(6.0, 2.0)])
    wall = 100.0
    t = 1.0
    for _ in range(6):  # inputs and the node's clock move: alive
        wall += DT
        cycle(core, robot, t)
        core.note_alive(wall)
        assert core.wall_watchdog(wall) is None
        t += DT
    speed = core.last_command.speed_mps
    assert speed > 0.1
    commands = []
    for k in range(1, 20):  # nothing arrives, the node's clock stands still; only the wall clock moves
        result = core.wall_watchdog(wall + k * DT)
        if k * DT <= core.settings.wall_timeout_s + 1e-9:
            assert result is None
            continue
        commands.append(result.command.speed_mps)
        assert "of wall time" in result.reasons[-1] and result.status["planner"]["source"] == "wall watchdog"
    assert commands[0] == pytest.approx(max(0.0, speed - STEP))
    assert all(b == pytest.approx(max(0.0, a - STEP)) for a, b in zip(commands[:-1], commands[1:]))
    assert commands[-1] == 0.0


def test_a_cycle_that_cannot_run_brakes_with_the_reason():
    """What the node publishes when a cycle raises (it catches it): one cycle's braking and why."""
    core = make_core()
    robot = Robot(people=[(6.0, 2.0)])
    t = drive_honestly(core, robot, 6)
    before = core.last_command
    result = core.fault_result(t, "cycle failed: RuntimeError: boom")
    assert_braking(result, before)
    assert result.reasons[-1] == "cycle failed: RuntimeError: boom" and "boom" in result.status["planner"]["events"]


def test_a_planner_that_raises_brakes_the_robot(monkeypatch):
    core = make_core()
    robot = Robot(people=[(6.0, 2.0)])
    t = drive_honestly(core, robot, 6)

    def boom(observation):
        raise RuntimeError("boom")

    monkeypatch.setattr(core.planner, "plan", boom)
    result, before = cycle(core, robot, t)
    assert_braking(result, before)
    assert result.mode in ("braking", "stopped") and "planner error: RuntimeError: boom" in result.reasons


def test_a_path_beyond_the_coordinate_bound_is_refused_and_the_old_one_kept():
    core = make_core()
    old = core.path
    for far in (1e308, -1e308, float("nan"), 2e6):
        with pytest.raises(ValueError, match="path waypoints"):
            core.set_path([[0.0, 0.0], [far, 0.0]])
        assert core.path is old
