"""Waiting outside a stream (:mod:`viapath.planning.viapath.stream_band`): the band's gap against brute force, and
holding short of a stream crossing the corridor, closed loop, oracle perception, judged by the simulator's gaps."""

from __future__ import annotations

import numpy as np
import pytest

from viapath.observation import Observation, Obstacles, RobotState
from viapath.path import DesignatedPath
from viapath.planning import make_planner
from viapath.planning.viapath.checks import LegChecks
from viapath.planning.viapath.stream_band import band_gaps, forecast_from
from viapath.scenarios import load_scenario
from viapath.sim.loop import run_episode
from viapath.sim.metrics import clearance_per_step


def _brute_gaps(points, starts, ends, radii, samples=4001):
    """Each point's gap to the union of discs centred at fine samples along each axis (an independent
    sampling; its error is at most half a sample spacing, on the side of a larger gap)."""
    s = np.linspace(0.0, 1.0, samples)
    gaps = np.full(len(points), np.inf)
    for a, b, r in zip(starts, ends, radii):
        centres = a[None] + s[:, None] * (b - a)[None]
        d = np.hypot(points[:, None, 0] - centres[None, :, 0], points[:, None, 1] - centres[None, :, 1]).min(axis=1)
        gaps = np.minimum(gaps, d - r)
    return gaps


def test_band_gaps_match_a_sampled_union_of_discs():
    rng = np.random.default_rng(5)
    for _ in range(20):
        n = int(rng.integers(1, 5))
        starts = rng.uniform(-3, 3, (n, 2))
        ends = starts + rng.uniform(-3, 3, (n, 2)) * (rng.random((n, 1)) > 0.2)  # some of zero length
        radii = rng.uniform(0.3, 1.0, n)
        points = rng.uniform(-5, 5, (200, 2))
        exact = band_gaps(points, starts, ends, radii)
        brute = _brute_gaps(points, starts, ends, radii)
        spacing = np.hypot(*(ends - starts).T).max() / 4000
        assert np.all(exact <= brute + 1e-9)
        assert np.all(brute - exact <= 0.5 * spacing + 1e-9)
        # inside the band exactly where some sampled disc holds the point
        assert np.array_equal(exact < -1e-6, brute < -1e-6) or np.all(
            np.abs(exact[(exact < 0) != (brute < 0)]) < spacing
        )


def test_no_people_no_band():
    gaps = band_gaps(np.zeros((3, 2)), np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0))
    assert np.all(np.isinf(gaps))


_STREAM = """
name: stream
description: a stream of people crossing the corridor ahead of the robot, blind to it
robot: {{start: [0.0, 0.0], heading: 0.0, speed: 0.3, radius: 0.25}}
path:
  waypoints: [[0.0, 0.0], [7.0, 0.0]]
  half_width: 1.5
obstacles:
{people}
duration_s: 60
"""

HOLD = {"stream_band_s": 5.0, "stream_band_entry_clearance_m": 0.3}  # the defaults, spelt out


@pytest.fixture(scope="module")
def stream_runs(tmp_path_factory):
    """Seven people crossing at x = 3 m, one every 2.5 s, at 0.8 m/s: with and without holding short."""
    people = "\n".join(
        f"  - {{start: [3.0, 4.0], velocity: [0.0, -0.8], radius: 0.25, start_time_s: {t}}}"
        for t in (2.0, 4.5, 7.0, 9.5, 12.0, 14.5, 17.0)
    )
    file = tmp_path_factory.mktemp("stream") / "stream.yaml"
    file.write_text(_STREAM.format(people=people))
    scenario = load_scenario(file)
    runs = {}
    for name, options in (("off", {"stream_band_s": 0.0}), ("hold", HOLD)):
        runs[name] = run_episode(
            scenario,
            perception="oracle",
            seed=0,
            position_noise_m=0.0,
            velocity_noise_mps=0.0,
            planner_overrides=options,
        )
    return runs


def test_holding_short_of_a_stream_keeps_clear_of_it_and_still_arrives(stream_runs):
    off, hold = stream_runs["off"], stream_runs["hold"]
    status = np.array(hold.trace.plan_status)
    assert (status == "hold-short").sum() >= 10
    # It waits before the stream's band (x = 3 m less the people's reach and the band's margin), not in it.
    held_x = hold.trace.robot_poses[status == "hold-short", 0]
    assert held_x.max() < 3.0 - 0.25 - 0.25 - 0.3
    assert hold.metrics["reached_goal"] and not hold.metrics["collision"]
    assert hold.metrics["time_outside_corridor_s"] == 0.0
    # The simulator's own gaps (surface to surface; these two runs: 0.43 m against 0.17 m without holding short,
    # where the robot waits and steps aside in the stream): at least the entry clearance asked for, and
    # arriving no more than 2 s later.
    gap_hold = clearance_per_step(hold.trace).min()
    assert gap_hold >= HOLD["stream_band_entry_clearance_m"]
    assert gap_hold >= clearance_per_step(off.trace).min() + 0.2
    assert hold.metrics["time_to_goal_s"] <= off.metrics["time_to_goal_s"] + 2.0


def test_a_stream_with_no_end_in_sight_is_not_waited_for(tmp_path):
    """Thirty people in single file 1.6 m apart crossing at x = 2.5 m at 0.8 m/s, all walking from the start: the
    stream lasts the whole run and the forecast never shows it ending within WAIT_LOOK_S. The robot does not begin
    to wait for it (these runs: 15 cycles of holding short, against 523 when a hold did not ask whether the stream
    ends, which holds the robot at the band's edge for the rest of the run) and keeps, as without holding short,
    clear of everyone (0.14 m against 0.141 m)."""
    people = "\n".join(
        f"  - {{start: [2.5, {2.0 + 1.6 * k:.2f}], velocity: [0.0, -0.8], radius: 0.25}}" for k in range(30)
    )
    file = tmp_path / "endless.yaml"
    file.write_text(_STREAM.format(people=people))
    scenario = load_scenario(file)
    runs = {
        name: run_episode(
            scenario, perception="oracle", seed=0, position_noise_m=0.0, velocity_noise_mps=0.0, planner_overrides=o
        )
        for name, o in (("off", {"stream_band_s": 0.0}), ("hold", HOLD))
    }
    status = np.array(runs["hold"].trace.plan_status)
    assert 0 < (status == "hold-short").sum() <= 20  # 2 s at most
    assert not runs["hold"].metrics["collision"]
    assert runs["hold"].metrics["time_outside_corridor_s"] == 0.0
    gap_off = clearance_per_step(runs["off"].trace).min()
    assert clearance_per_step(runs["hold"].trace).min() >= gap_off - 0.01


def test_the_forecast_seen_from_later_is_the_same_cone_at_the_same_times():
    """forecast_from(t0) at t' must be the leg checks' cone at t0 + t': centre p + v (t0 + t'), radius
    r + g min(t0 + t', cap), sampled here directly from the checks' own fields."""
    path = DesignatedPath([[0.0, 0.0], [5.0, 0.0]], half_width_m=1.0)
    planner = make_planner("viapath", path, nominal_speed_mps=0.2)
    people = Obstacles(
        np.array([[1.0, -1.0], [3.0, 0.5]]),
        np.array([[0.0, 0.8], [-0.5, 0.1]]),
        np.array([0.25, 0.3]),
        position_sigma_m=np.array([0.05, 0.1]),
        velocity_sigma_mps=np.array([0.1, 0.3]),
    )
    observation = Observation(0.0, RobotState(np.zeros(2), 0.0, 0.1, 0.0, 0.25), people)
    checks = LegChecks.of(
        planner.situation(observation), planner.config, planner.subgoals, planner.subgoal_policy, 0.25
    )
    p, v, r, g, cap = checks.packed_obstacles()
    assert np.all(g > 0)  # the cones grow: the test would not see a wrong cap otherwise
    for t0 in (0.0, 0.4, 1.3, 5.0):
        p2, v2, r2, g2, cap2 = forecast_from(checks, t0)
        for t in np.linspace(0.0, 4.0, 41):
            np.testing.assert_allclose(p2 + v2 * t, p + v * (t0 + t), atol=1e-12)
            np.testing.assert_allclose(r2 + g2 * np.minimum(t, cap2), r + g * np.minimum(t0 + t, cap), atol=1e-12)
