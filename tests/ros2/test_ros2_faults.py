"""Faults with the node running (over DDS, separate processes): each time the command stays finite
and inside the limits, and the robot stops where it must.

Two episodes on an empty straight corridor (nominal 0.3 m/s), each a sequence of faults injected by
the simulator node (``--fault KIND@T-END``), checked window by window on the simulator's true
robot motion and on what the node reported in its DiagnosticArray:

* front scanner silent (1.0-2.2 s), then sending NaN ranges (3.0-4.2 s): the way ahead is blind ->
  the robot stops;
* odometry stopped (5.0-6.4 s): the robot brakes to a stop within its limits;
* the clock jumps back 3 s (at 7.5 s): tracks reset, the robot is held for ``reset_hold_s`` (0.5 s),
  then goes on;
* rear scanner silent (1.0-2.5 s), then sending short scans (3.5-5.0 s): speed capped at
  0.8 * (0.3 / 1.0 - 0.1) = 0.16 m/s.
"""

from __future__ import annotations

import numpy as np
import pytest

from viapath.ros2 import rclpy_available

OK, WHY = rclpy_available()
pytestmark = pytest.mark.skipif(not OK, reason=WHY)


CAP_MPS = 0.8 * (0.3 / 1.0 - 0.1)


@pytest.fixture(scope="module")
def fault_runs(ros2_launcher):
    return ros2_launcher.faults()


def window(trace, start, end):
    t = trace["time_s"]
    return (t >= start - 1e-9) & (t <= end + 1e-9)


@pytest.mark.parametrize("run", ["front", "rear"])
def test_commands_stay_finite_and_inside_the_limits(fault_runs, run):
    _, trace, _ = fault_runs[run]
    v, w, speed = trace["cmd_speed_mps"][:-1], trace["cmd_turn_rate_radps"][:-1], trace["speed_mps"][:-1]
    assert len(v) > 55
    assert np.all(np.isfinite(v)) and np.all(np.isfinite(w))
    assert np.all((v >= 0.0) & (v <= 0.6 + 1e-9)) and np.all(np.abs(w) <= 2.0 + 1e-9)
    # Never more than one cycle's acceleration from the speed the node last saw; that odometry can be
    # one cycle old when the machine is loaded (the fault runs are not lock-stepped), hence two cycles.
    assert np.all(np.abs(v - speed) <= 2 * 0.8 * 0.1 + 1e-6)
    assert np.all(np.abs(trace["lateral_deviation_m"]) < 0.05)


def test_front_scanner_silent_stops_the_robot_and_it_goes_on_after(fault_runs):
    _, trace, statuses = fault_runs["front"]
    speed = trace["speed_mps"]
    # silent from 1.0 s: blind after 0.3 s (+ one cycle), then at most 0.3 / 0.8 = 0.375 s of braking
    assert np.all(speed[window(trace, 1.0 + 0.3 + 0.2 + 0.375, 2.2)] == 0.0)
    assert speed[window(trace, 2.2, 3.0)].max() >= 0.25
    assert any("silent: front" in s.get("reasons", "") and s.get("mode") == "degraded" for s in statuses)


def test_nan_ranges_stop_the_robot(fault_runs):
    _, trace, _statuses = fault_runs["front"]
    assert np.all(trace["speed_mps"][window(trace, 3.0 + 0.3 + 0.2 + 0.375, 4.2)] == 0.0)
    assert trace["speed_mps"][window(trace, 4.2, 5.0)].max() >= 0.25


def test_stopped_odometry_brakes_to_a_stop(fault_runs):
    _, trace, statuses = fault_runs["front"]
    speed = trace["speed_mps"]
    assert speed[window(trace, 4.8, 5.0)].min() >= 0.25  # driving before
    assert np.all(speed[window(trace, 5.0 + 0.5 + 0.2 + 0.375, 6.4)] == 0.0)
    assert any("no odometry" in s.get("reasons", "") for s in statuses)


def test_clock_jump_back_holds_the_robot_then_it_goes_on(fault_runs):
    _, trace, statuses = fault_runs["front"]
    speed = trace["speed_mps"]
    assert speed[window(trace, 7.2, 7.5)].min() >= 0.25
    # Braked at the limit while held (0.5 s): from 0.3 m/s, 4 cycles to a stop. The fault runs are not
    # lock-stepped, so on a loaded machine one of the hold's cycles can act on odometry a cycle old
    # and the hold ends one braking step short (0.06 m/s; seen once in a full-suite run).
    held = speed[window(trace, 7.5, 8.3)]
    assert held.min() <= 0.3 - 3 * 0.8 * 0.1 + 1e-6
    assert speed[window(trace, 8.8, 9.5)].max() >= 0.2  # going again (a loaded machine may resume a cycle late)
    assert any("holding after a time jump backwards" in s.get("reasons", "") for s in statuses)


def test_rear_scanner_silent_or_short_caps_the_speed(fault_runs):
    _, trace, statuses = fault_runs["rear"]
    speed = trace["speed_mps"]
    for start, end in ((1.0, 2.5), (3.5, 5.0)):
        capped = speed[window(trace, start + 0.3 + 0.2 + 0.2, end)]
        assert np.all(capped <= CAP_MPS + 1e-6) and capped.min() >= CAP_MPS - 0.02  # slower, but still driving
        assert speed[window(trace, end + 0.4, end + 1.0)].max() >= 0.25  # and back to nominal after
    assert any("length" in s.get("reasons", "") or "silent: rear" in s.get("reasons", "") for s in statuses)


@pytest.fixture(scope="module")
def hostile_run(ros2_launcher):
    return ros2_launcher.hostile()


def _planner(phase):
    return [s for s in phase["statuses"] if s["_name"] == "planner"]


def test_a_malformed_first_scan_is_refused_and_the_node_lives_on(hostile_run):
    phases, node_alive, node_err = hostile_run
    assert node_alive, node_err[-2000:]
    scanner = [
        s
        for s in phases["malformed_first_scan"]["statuses"] + phases["driving"]["statuses"]
        if s["_name"] == "scanner laser"
    ]
    assert any("layout: 1" in s["refused"] and "not below range_max" in s["last_problem"] for s in scanner), scanner[
        -1:
    ]
    assert phases["driving"]["commands"][-1][1] >= 0.15  # and it drives on the good scans that follow


def test_a_zero_quaternion_is_an_odometry_fault_and_the_robot_brakes(hostile_run):
    phases, _, _ = hostile_run
    statuses = _planner(phases["zero_quaternion"])
    assert any("odometry fault: orientation" in s["reasons"] for s in statuses), [s["reasons"] for s in statuses]
    speeds = [c[1] for c in phases["zero_quaternion"]["commands"]]
    assert speeds and all(b <= a + 1e-9 for a, b in zip(speeds[:-1], speeds[1:]))
    assert phases["after_quaternion"]["commands"][-1][1] >= 0.15  # driving again after reset_hold_s


def test_with_odometry_stale_one_command_per_cycle_the_watchdog_adds_none(hostile_run):
    """Scans go on for 2 s of simulated time (lock-step) without odometry: each cycle brakes for it, and the
    watchdog, which brakes for the same reason, sends nothing beside them: 10 commands a second, not 20."""
    from _hostile_driver import ODOMETRY_STALE_STEPS

    phases, _, _ = hostile_run
    phase = phases["odometry_stale"]
    statuses = _planner(phase)
    assert sum("no odometry" in s["reasons"] for s in statuses) >= ODOMETRY_STALE_STEPS // 2
    assert sum(s["source"] == "cycle" for s in statuses) >= ODOMETRY_STALE_STEPS - 1
    seconds = ODOMETRY_STALE_STEPS * 0.1
    assert len(phase["commands"]) <= 10.5 * seconds, [s["source"] for s in statuses]
    assert not any(s["source"] == "watchdog" for s in statuses)
    assert phase["commands"][-1][1] == 0.0  # braked to rest meanwhile


def test_an_empty_path_stops_the_robot(hostile_run):
    phases, _, _ = hostile_run
    statuses = _planner(phases["empty_path"])
    assert any("designated path cleared by an empty path" in s["reasons"] for s in statuses)
    assert phases["empty_path"]["commands"][-1][1] == 0.0


def test_when_clock_and_inputs_stop_the_node_still_brakes_on_the_wall_clock(hostile_run):
    phases, _, _ = hostile_run
    phase = phases["clock_stops"]
    stop_wall, speed = phase["stopped_at_wall"]["wall"], phase["stopped_at_wall"]["speed"]
    assert speed >= 0.15
    after = [(w - stop_wall, v) for w, v, _ in phase["commands"] if w > stop_wall]
    assert after, "no command after /clock and the inputs stopped"
    assert 0.3 <= after[0][0] <= 1.5, after[:3]  # wall_timeout_s (0.5 s) after the last input, give or take a load
    speeds = [v for _, v in after]
    assert speeds[0] <= speed - 0.08 + 1e-6 and all(b <= a + 1e-9 for a, b in zip(speeds[:-1], speeds[1:]))
    assert speeds[-1] == 0.0
    assert any("of wall time" in s["reasons"] and s["source"] == "wall watchdog" for s in _planner(phase))
