"""The node's cycle logic without ROS: bad input refused and reported, safe stops, limits always kept.

Checks :class:`viapath.ros2.core.PlannerCore` directly (no rclpy, no DDS). Blind-sector claims are
checked against an independent sampling of the scanners' fields of view, not against the code
that makes them.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from viapath.perception.raycast import simulate_scan
from viapath.perception.scanner import ScannerModel
from viapath.ros2.core import PlannerCore
from viapath.ros2.settings import validate
from viapath.static import point_segment_distances

SCANNERS = (ScannerModel.urg04lx("front", "forward"), ScannerModel.urg04lx("rear", "backward"))
FRAMES = ("laser_front", "laser_rear")


def make_core(**values) -> PlannerCore:
    core = PlannerCore(validate(values))
    core.set_path([[0.0, 0.0], [5.0, 0.0]])
    return core


def scans_at(pose, people=np.array([[2.0, 0.0]])):
    radii = np.full(len(people), 0.25)
    return [simulate_scan(s, np.asarray(pose, float), people, radii) for s in SCANNERS]


def feed(core, t, pose=None, speed=0.2, scans=None, which=(0, 1), odom=True):
    """Odometry and scans at ``t``; without ``pose`` the robot drives along x at ``speed`` (honest odometry:
    the pose moves as the twist says)."""
    if pose is None:
        last = getattr(core, "_fed", None)
        x = 0.0 if last is None else last[1] + 0.5 * (last[2] + speed) * (t - last[0])
        core._fed = (t, x, speed)
        pose = (x, 0.0, 0.0)
    if odom:
        core.on_odometry(t, t, "odom", pose[0], pose[1], pose[2], speed, 0.0)
    scans = scans_at(pose) if scans is None else scans
    due = False
    for i in which:
        s = SCANNERS[i]
        due = core.on_scan(i, t, t, FRAMES[i], s.angle_min_rad, s.angle_increment_rad, scans[i])
    return due


def check_command(core, command, measured_speed, before=None):
    """Finite, inside the limits, at most one cycle's acceleration above the measured speed and at most one
    cycle's braking below the lower of it and the command ``before`` (when given)."""
    lim = core.limits
    dt = core.settings.cycle_period_s
    assert math.isfinite(command.speed_mps) and math.isfinite(command.turn_rate_radps)
    assert 0.0 <= command.speed_mps <= lim.max_speed_mps + 1e-12
    assert abs(command.turn_rate_radps) <= lim.max_turn_rate_radps + 1e-12
    measured = min(max(measured_speed, 0.0), lim.max_speed_mps)
    assert command.speed_mps <= measured + lim.max_accel_mps2 * dt + 1e-9
    low = measured if before is None else min(measured, before.speed_mps)
    assert command.speed_mps >= low - lim.max_accel_mps2 * dt - 1e-9


def test_a_normal_cycle_drives_and_tracks_the_person():
    core = make_core()
    for k in range(6):
        assert feed(core, 1.0 + 0.1 * k)
        result = core.cycle(1.0 + 0.1 * k)
    assert result.mode == "driving" and result.reasons == []
    assert len(result.obstacles) == 1 and np.allclose(result.obstacles.positions[0], [2.0, 0.0], atol=0.1)
    assert result.command.speed_mps > 0.0


@pytest.mark.parametrize(
    "fault, reason",
    [
        ("nan", "invalid"),
        ("zeros", "invalid"),
        ("short", "length"),
        ("frame", "frame"),
        ("angles", "angles"),
    ],
)
def test_bad_scans_are_refused_and_counted(fault, reason):
    core = make_core()
    s = SCANNERS[0]
    ranges = scans_at((0.0, 0.0, 0.0))[0]
    frame, angle_min = FRAMES[0], s.angle_min_rad
    if fault == "nan":
        ranges = np.full_like(ranges, np.nan)
    elif fault == "zeros":
        ranges = np.zeros_like(ranges)
    elif fault == "short":
        ranges = ranges[:-10]
    elif fault == "frame":
        frame = "somewhere_else"
    elif fault == "angles":
        angle_min += 0.2
    assert not core.on_scan(0, 1.0, 1.0, frame, angle_min, s.angle_increment_rad, ranges)
    assert core.health[0].refused == {reason: 1} and core.health[0].good == 0
    result = core.cycle(1.0)
    assert result.status["scanner front"]["state"] != "ok" and reason in result.status["scanner front"]["refused"]


def test_inf_readings_are_no_return_not_a_failure():
    core = make_core()
    s = SCANNERS[0]
    core.on_scan(0, 1.0, 1.0, FRAMES[0], s.angle_min_rad, s.angle_increment_rad, np.full(s.beam_count, np.inf))
    assert core.health[0].good == 1 and core.health[0].refused == {}


def test_no_scan_brakes_to_a_stop_within_the_limits():
    core = make_core(nominal_speed_mps=0.5)
    speed = 0.5
    for k in range(3):
        feed(core, 1.0 + 0.1 * k, speed=speed)
        speed = core.cycle(1.0 + 0.1 * k).command.speed_mps
    speed = start = core.last_command.speed_mps  # the base follows the commands
    speeds = []
    x = core._fed[1]
    for k in range(12):  # scans stop; odometry goes on, the robot slows as commanded
        t = 1.3 + 0.1 * k
        x += 0.1 * speed
        core.on_odometry(t, t, "odom", x, 0.0, 0.0, speed, 0.0)
        result = core.watchdog(t)
        if t - 1.2 <= 0.3 + 1e-9:
            assert result is None  # within the timeout the scan cycles are still expected
            continue
        check_command(core, result.command, speed)
        assert "no scan for 0.3 s" in result.reasons
        speed = result.command.speed_mps
        speeds.append(speed)
    assert speeds[-1] == 0.0 and result.mode == "stopped"
    # hardest braking: at 0.8 m/s² one tick takes 0.08 m/s off the speed the robot had when scans stopped
    assert speeds.index(0.0) == math.ceil(start / (0.8 * 0.1) - 1e-9) - 1


def test_one_command_per_period_the_watchdog_only_when_no_cycle_ran():
    """Scans every 0.1 s, odometry stops at 1.9 s (stale from 2.4 s), scans stop after 3.9 s; the watchdog ticks
    every 0.1 s between the scans. While scans arrive the cycles brake for the stale odometry and the watchdog
    adds nothing; once they stop, the watchdog brakes within 2.5 periods of the last cycle, then every tick."""
    core = make_core(nominal_speed_mps=0.5)
    sent: list[tuple[float, str, float]] = []  # (node time, source, speed)
    for k in range(40):
        t = 1.0 + 0.1 * k
        if k < 30 and feed(core, t, speed=core.last_command.speed_mps, odom=k < 10):
            result = core.cycle(t)
            sent.append((t, "cycle", result.command.speed_mps))
            if k >= 15:
                assert any("no odometry" in r for r in result.reasons)
        tick = t + 0.03
        result = core.watchdog(tick)
        if result is not None:
            sent.append((tick, "watchdog", result.command.speed_mps))
    times = np.array([t for t, _, _ in sent])
    sources = [s for _, s, _ in sent]
    assert sources.count("cycle") == 30 and all(s == "cycle" for s in sources[:30])
    last_cycle = times[29]
    assert 0.1 < times[30] - last_cycle <= 2.5 * 0.1 + 1e-9  # the watchdog takes over
    assert np.allclose(np.diff(times[30:]), 0.1)  # every tick after
    for start in np.arange(1.0, 5.0, 0.01):  # at most one command per period in every second
        assert np.count_nonzero((times >= start) & (times < start + 1.0 - 1e-9)) <= 10
    assert sent[-1][2] == 0.0


def test_a_cleared_path_brakes_at_max_accel_with_the_watchdog_ticking_between_cycles():
    """Driving at 0.5 m/s, the path cleared; scans and (honest) odometry go on, the watchdog ticks between the
    cycles. Each 0.1 s takes 0.8 m/s² x 0.1 s = 0.08 m/s off, not more: one braking command per period (a
    watchdog command beside each cycle's braked twice as hard)."""
    core = make_core(nominal_speed_mps=0.5)
    far = np.array([[50.0, 30.0]])
    speed = 0.0
    for k in range(20):
        t = 1.0 + 0.1 * k
        feed(core, t, speed=speed, scans=scans_at((0.0, 0.0, 0.0), far))
        speed = core.cycle(t).command.speed_mps
    assert speed == pytest.approx(0.5)
    core.clear_path()
    speeds = [speed]
    for k in range(20, 30):
        t = 1.0 + 0.1 * k
        feed(core, t, speed=core.last_command.speed_mps, scans=scans_at((0.0, 0.0, 0.0), far))
        core.cycle(t)
        core.watchdog(t + 0.05)
        speeds.append(core.last_command.speed_mps)
    assert np.allclose(-np.diff(speeds)[:6], 0.08) and speeds[-1] == 0.0, speeds


def test_no_odometry_brakes_from_the_last_command_to_zero():
    core = make_core()
    for k in range(3):
        feed(core, 1.0 + 0.1 * k, speed=0.3)
        core.cycle(1.0 + 0.1 * k)
    core.last_command = type(core.last_command)(0.3, 0.5)
    commands = []
    for k in range(1, 15):  # scans go on, odometry stopped at 1.2 s
        t = 1.2 + 0.1 * k
        feed(core, t, odom=False)
        commands.append(core.cycle(t).command)
    late = [c for c, k in zip(commands, range(1, 15)) if 0.1 * k > 0.5 + 1e-9]
    assert all(abs(a.speed_mps - b.speed_mps) <= 0.08 + 1e-9 for a, b in zip(late[:-1], late[1:]))
    assert late[-1].speed_mps == 0.0 and late[-1].turn_rate_radps == 0.0


def _blind_ahead_brute_force(scanners, robot_radius_m: float, cone_rad: float) -> bool:
    """Independent check: sample points ahead beyond the body; is any of them outside every field of view?"""
    for angle in np.linspace(-cone_rad, cone_rad, 61):
        for r in np.linspace(robot_radius_m + 0.02, 3.0, 60):
            p = np.array([r * math.cos(angle), r * math.sin(angle)])
            seen = False
            for s in scanners:
                d = p - np.array([s.mount_x_m, s.mount_y_m])
                bearing = math.atan2(
                    math.sin(math.atan2(d[1], d[0]) - s.mount_yaw_rad),
                    math.cos(math.atan2(d[1], d[0]) - s.mount_yaw_rad),
                )
                seen |= abs(bearing) <= s.field_of_view_rad / 2 and s.range_min_m <= np.hypot(*d) <= s.range_max_m
            if not seen:
                return True
    return False


@pytest.mark.parametrize("silent", [0, 1])
def test_one_scanner_silent_marks_its_sector_blind_and_limits_the_speed(silent):
    # feed's odometry drives straight: the paper's weights stay behind the standing person (the default
    # weights turn to pass it, which this odometry would report as a fault).
    core = make_core(weights_preset="paper")
    live = 1 - silent
    for k in range(3):
        feed(core, 1.0 + 0.1 * k)
        core.cycle(1.0 + 0.1 * k)
    speed = 0.2
    for k in range(3, 12):  # the base follows the command exactly
        t = 1.0 + 0.1 * k
        due = feed(core, t, speed=speed, which=(live,))
        if due:  # the first lone scan waits one period for the other scanner
            result = core.cycle(t)
            speed = result.command.speed_mps
    assert result.mode == "degraded"
    blind_ahead = _blind_ahead_brute_force([SCANNERS[live]], 0.25, math.radians(30))
    assert blind_ahead == (silent == 0)  # the front scanner silent leaves the way ahead unseen
    expected_cap = 0.0 if blind_ahead else 0.8 * (0.3 / 1.0 - 0.1)
    assert result.speed_cap_mps == pytest.approx(expected_cap)
    assert result.command.speed_mps <= max(expected_cap, 0.2 - 9 * 0.08) + 1e-9
    assert result.blind_sectors_rad and "silent: " + ("front" if silent == 0 else "rear") in result.reasons[-1]


def test_time_jump_backwards_resets_and_holds_the_robot():
    core = make_core()
    for k in range(5):
        feed(core, 5.0 + 0.1 * k)
        core.cycle(5.0 + 0.1 * k)
    assert len(core.tracker) > 0
    speeds = []
    speed = 0.2
    for k in range(10):
        t = 3.0 + 0.1 * k  # the clock went back 2.5 s
        feed(core, t, speed=speed)
        before = core.last_command
        result = core.cycle(t)
        check_command(core, result.command, speed, before)
        speed = result.command.speed_mps
        speeds.append((t, speed, result.mode))
    assert any("time jump backwards" in e for e in core.events)
    held = [v for t, v, _ in speeds if t < 3.0 + 0.5 - 1e-9]
    assert all(a >= b for a, b in zip(held[:-1], held[1:]))  # braking while held
    assert speeds[-1][2] == "driving" and speeds[-1][1] > 0.0


@settings(max_examples=15, deadline=None, derandomize=True)
@given(
    garbage=st.lists(
        st.sampled_from([0.0, -1.0, float("nan"), float("inf"), float("-inf"), 1e9, 0.3, 1.5, 4.0]),
        min_size=683,
        max_size=683,
    ),
    speed=st.floats(-1.0, 2.0),
    turn=st.floats(-5.0, 5.0),
    heading=st.floats(-10.0, 10.0),
)
def test_any_scan_and_odometry_give_a_finite_command_inside_the_limits(garbage, speed, turn, heading):
    core = make_core()
    s = SCANNERS[0]
    ranges = np.array(garbage, dtype=float)
    for k in range(3):
        t = 1.0 + 0.1 * k
        core.on_odometry(t, t, "odom", 0.5, 0.1, heading, speed, turn)
        core.on_scan(0, t, t, FRAMES[0], s.angle_min_rad, s.angle_increment_rad, ranges)
        core.on_scan(1, t, t, FRAMES[1], s.angle_min_rad, s.angle_increment_rad, np.roll(ranges, 7))
        before = core.last_command  # a stop before anything was commanded
        result = core.cycle(t)
        c = result.command
        assert math.isfinite(c.speed_mps) and math.isfinite(c.turn_rate_radps)
        assert 0.0 <= c.speed_mps <= core.limits.max_speed_mps
        assert abs(c.turn_rate_radps) <= core.limits.max_turn_rate_radps
        step = core.limits.max_accel_mps2 * 0.1 + 1e-9
        if core.odometry_trusted(t):  # within one cycle's acceleration of the measured speed, or slower
            v_meas = min(max(speed, 0.0), core.limits.max_speed_mps)
            assert c.speed_mps <= v_meas + step
            assert c.speed_mps >= min(v_meas, before.speed_mps) - step
        else:  # a refused measurement is no base: braking from what was commanded
            assert "odometry" in result.status["planner"]["reasons"]
            assert c.speed_mps <= max(0.0, before.speed_mps - step + 2e-9)


@pytest.mark.parametrize("use_shield, expected", [("default", True), ("off", False)])
def test_the_shield_wraps_the_planner_and_its_verdict_is_reported(use_shield, expected):
    from viapath.safety import ShieldedPlanner

    core = make_core(use_shield=use_shield, **{"shield.mode": "passive-friendly"})
    assert isinstance(core.planner, ShieldedPlanner) == expected
    for k in range(5):
        feed(core, 1.0 + 0.1 * k)
        result = core.cycle(1.0 + 0.1 * k)
    assert ("shield" in result.status) == expected
    if expected:
        assert core.planner.shield.config.mode == "passive-friendly"
        assert result.status["shield"]["intervened"] in ("True", "False")
        assert result.status["planner"]["shield_mode"] == "passive-friendly"


@pytest.mark.parametrize("static_after_s, people_left", [(3.0, 0), (0.0, 1)])
def test_a_track_standing_still_is_static_unless_the_node_is_told_never(static_after_s, people_left):
    """The node's tracker turns a track that stands still for tracker_static_after_s into static geometry (its
    returns reach the static layer); 0 keeps it a person."""
    core = make_core(tracker_static_after_s=static_after_s)
    pose = (0.0, 0.0, 0.0)
    for k in range(45):  # 4.5 s, the robot at rest, someone standing 2 m ahead
        t = 1.0 + 0.1 * k
        feed(core, t, pose=pose, speed=0.0)
        result = core.cycle(t)
    assert len(result.obstacles) == people_left
    near = (
        point_segment_distances(np.array([[2.0, 0.0]]), core.static_now.segments).min()
        if len(core.static_now)
        else np.inf
    )
    assert (near < 0.4) == (people_left == 0)
