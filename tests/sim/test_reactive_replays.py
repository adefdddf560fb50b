"""Reactive replays (issue 11 item 4): recorded people give way to the robot and return to their track."""

from pathlib import Path

import numpy as np
import pytest
from pydantic import ValidationError

from viapath.bench.suites import data_root, generate_suite
from viapath.io.eth_ucy import load_tracks, replay_states
from viapath.scenarios.models import Scenario
from viapath.sim.loop import run_episode
from viapath.sim.obstacles import scenario_obstacle_states
from viapath.sim.reactive import ReactiveReplay, obstacle_motion

ETH_UCY = data_root() / "eth_ucy_trajectron"
needs_data = pytest.mark.skipif(not ETH_UCY.is_dir(), reason=f"ETH/UCY data not found at {ETH_UCY} (set VIAPATH_DATA)")

ROW_S = 0.4
WALK_MPS = 1.2


def write_track(folder: Path, start=(-6.0, 0.0), velocity=(WALK_MPS, 0.0), rows=41, ped_id=1, first_row=0) -> Path:
    """One straight-line walker in the 4-column ETH/UCY format (row step 10 frames = ROW_S s)."""
    k = np.arange(rows)
    t = k * ROW_S
    table = np.column_stack(
        [(first_row + k) * 10, np.full(rows, ped_id), start[0] + velocity[0] * t, start[1] + velocity[1] * t]
    )
    file = folder / f"walker{ped_id}.txt"
    np.savetxt(file, table, fmt="%.6f", delimiter="\t")
    return file


def episode_times(duration_s=16.0, dt_s=0.1):
    return np.arange(int(round(duration_s / dt_s)) + 1) * dt_s


def drive(replay: ReactiveReplay, robot_at):
    """Step the replay with the robot at ``robot_at(k)`` (standing still); returns robot positions per row."""
    robot = np.array([robot_at(k) for k in range(len(replay.times))], float)
    for k in range(len(replay.times) - 1):
        replay.step(robot[k], np.zeros(2))
    return robot


def surface_gap(positions, robot, radii_sum=0.5):
    return np.hypot(*(positions - robot).T) - radii_sum


def test_reactive_person_steps_aside_for_a_robot_standing_on_their_track(tmp_path):
    tracks = load_tracks(write_track(tmp_path), ROW_S)
    times = episode_times()
    recorded, _ = replay_states(tracks, times, ROW_S)
    robot = np.zeros((len(times), 2))  # robot centre exactly on the recorded line, at x = 0
    passive_gap = surface_gap(recorded[:, 0], robot)
    assert np.nanmin(passive_gap) < -0.45  # the recording walks straight through the robot

    reactive = ReactiveReplay(tracks, times, 0.0, ROW_S)
    drive(reactive, lambda k: (0.0, 0.0))
    path = reactive.positions[:, 0]
    gap = surface_gap(path, robot)
    assert np.nanmin(gap) > 0.15  # never touches it
    assert np.nanmax(np.abs(path[:, 1])) > 0.5  # by stepping aside
    assert path[-1, 0] > 5.0  # and gets past it, not stopped in front
    # Exact tie (robot dead ahead on the line): the walker keeps right, i.e. to -y walking along +x.
    assert path[np.nanargmax(np.abs(path[:, 1])), 1] < 0
    # Speed cap: max(1.3 * 1.2, 1.0) m/s, checked on the positions themselves.
    speeds = np.hypot(*np.diff(path, axis=0).T) / np.diff(times)
    assert np.nanmax(speeds) <= 1.3 * WALK_MPS + 1e-9


def test_the_side_follows_the_robot_offset(tmp_path):
    tracks = load_tracks(write_track(tmp_path), ROW_S)
    times = episode_times()
    sides = []
    for robot_y in (-0.2, 0.2):
        reactive = ReactiveReplay(tracks, times, 0.0, ROW_S)
        drive(reactive, lambda k, robot_y=robot_y: (0.0, robot_y))
        y = reactive.positions[:, 0, 1]
        sides.append(y[np.nanargmax(np.abs(y))])
        assert np.nanmin(surface_gap(reactive.positions[:, 0], np.array([0.0, robot_y]))) > 0.15
    assert sides[0] > 0.3 and sides[1] < -0.3  # robot a little right -> pass on the left, and vice versa


def test_reactive_track_returns_to_the_recording_once_the_robot_is_gone(tmp_path):
    tracks = load_tracks(write_track(tmp_path), ROW_S)
    times = episode_times()
    recorded, _ = replay_states(tracks, times, ROW_S)
    reactive = ReactiveReplay(tracks, times, 0.0, ROW_S)
    gone_at = 50  # at 5.0 s, when the walker is being pushed aside, the robot is taken away
    drive(reactive, lambda k: (0.0, 0.0) if k < gone_at else (100.0, 100.0))
    deviation = np.hypot(*(reactive.positions[:, 0] - recorded[:, 0]).T)
    assert deviation[gone_at] > 0.2  # it had been disturbed
    after = deviation[gone_at:]
    assert after[40] < 0.5 * deviation[gone_at]  # 4 s later: less than half the deviation
    assert after[80] < 0.02  # 8 s later: back on the recording within 2 cm
    # Critically damped (T_back = 4 tau): once it has turned back it does not overshoot: the signed
    # lateral deviation never changes sign after the robot is gone.
    lateral = reactive.positions[gone_at:, 0, 1] - recorded[gone_at:, 0, 1]
    assert np.all(np.sign(lateral[np.abs(lateral) > 1e-3]) == np.sign(lateral[0]))


def test_undisturbed_reactive_people_stay_exactly_on_the_recording(tmp_path):
    tracks = load_tracks(write_track(tmp_path), ROW_S) + load_tracks(
        write_track(tmp_path, start=(0.0, -5.0), velocity=(0.0, 0.9), rows=20, ped_id=2, first_row=10), ROW_S
    )
    times = episode_times()
    recorded, recorded_velocity = replay_states(tracks, times + 0.7, ROW_S, offset=(3.0, -1.0))
    reactive = ReactiveReplay(tracks, times, 0.7, ROW_S, offset=(3.0, -1.0))
    drive(reactive, lambda k: (500.0, 500.0))
    np.testing.assert_array_equal(np.isnan(reactive.positions), np.isnan(recorded))  # same presence
    np.testing.assert_allclose(reactive.positions, recorded, atol=1e-12, equal_nan=True)
    np.testing.assert_allclose(reactive.velocities, recorded_velocity, atol=1e-12, equal_nan=True)


def test_reported_velocity_is_a_backward_difference_of_the_actual_positions(tmp_path):
    tracks = load_tracks(write_track(tmp_path), ROW_S)
    times = episode_times()
    reactive = ReactiveReplay(tracks, times, 0.0, ROW_S)
    drive(reactive, lambda k: (0.0, 0.1))
    rows_per_step = 4  # ROW_S / 0.1 s
    p, v = reactive.positions[:, 0], reactive.velocities[:, 0]
    brute = (p[rows_per_step:] - p[:-rows_per_step]) / ROW_S
    np.testing.assert_allclose(v[rows_per_step:], brute, atol=1e-9)
    assert np.nanmax(np.abs(v[:, 1])) > 0.3  # the sidestep shows in the velocity given to planners


def scenario_with(file: Path, react: bool, extra_obstacles=()):
    return Scenario.model_validate(
        {
            "name": "stand-on-track",
            "robot": {"start": [0.0, 0.0], "heading": 1.5707963, "speed": 0.2, "radius": 0.25},
            "path": {"waypoints": [[0.0, 0.0], [0.0, 6.0]], "half_width": 1.0},
            "obstacles": [{"replay": {"file": str(file), "dt_s": ROW_S, "react": react}}, *extra_obstacles],
            "duration_s": 14.0,
        }
    )


@pytest.fixture
def standstill(monkeypatch):
    """A planner that always commands a stop (registered for this test only)."""
    from viapath.observation import Command
    from viapath.planning import Decision, Plan, Planner
    from viapath.planning.base import PLANNERS

    monkeypatch.setattr(PLANNERS, "_entries", dict(PLANNERS._entries))

    class Standstill(Planner, name="test-standstill"):
        def decide(self, situation):
            return Decision(Command.stop(), Plan("stop", 0.0, situation.position))

    return "test-standstill"


def test_closed_loop_robot_at_rest_is_walked_into_only_by_non_reactive_people(tmp_path, standstill):
    file = write_track(tmp_path)  # walks along +x through the robot's start at t = 5 s
    passive = run_episode(scenario_with(file, react=False), planner=standstill)
    reactive = run_episode(scenario_with(file, react=True), planner=standstill)
    assert passive.metrics["collision"] and passive.metrics["min_clearance_m"] < -0.4
    assert not passive.metrics["at_fault_collision"]  # the robot was at rest: not its fault
    assert not reactive.metrics["collision"] and reactive.metrics["min_clearance_m"] > 0.15
    # The trace holds where the reactive person actually was (metrics are computed from it; the
    # metric's clearance is continuous in time, so at most a little below the sampled one).
    robot = reactive.trace.robot_poses[:, :2]
    gaps = surface_gap(reactive.trace.obstacle_positions[:, 0], robot)
    assert 0.0 <= np.nanmin(gaps) - reactive.metrics["min_clearance_m"] < 0.01


def test_non_reactive_obstacles_keep_their_precomputed_states_beside_reactive_ones(tmp_path, standstill):
    file = write_track(tmp_path)
    walker = {"start": [3.0, 3.0], "velocity": [-0.3, 0.0], "radius": 0.25}
    plain = scenario_with(file, react=False, extra_obstacles=[walker])
    assert obstacle_motion(plain, episode_times(14.0)) is None  # nobody reacts: the old code path
    episode = run_episode(plain, planner=standstill)
    expected, expected_v, _ = scenario_obstacle_states(plain, episode.trace.times_s)
    np.testing.assert_array_equal(episode.trace.obstacle_positions, expected)
    np.testing.assert_array_equal(episode.trace.obstacle_velocities, expected_v)

    mixed = Scenario.model_validate(
        {
            **plain.model_dump(),
            "obstacles": [
                {"replay": {"file": str(file), "dt_s": ROW_S, "react": True}},
                {"replay": {"file": str(file), "dt_s": ROW_S}},
                walker,
            ],
        }
    )
    episode = run_episode(mixed, planner=standstill)
    expected, expected_v, _ = scenario_obstacle_states(mixed, episode.trace.times_s)
    np.testing.assert_array_equal(episode.trace.obstacle_positions[:, 1:], expected[:, 1:])
    np.testing.assert_array_equal(episode.trace.obstacle_velocities[:, 1:], expected_v[:, 1:])
    assert np.nanmax(np.abs(episode.trace.obstacle_positions[:, 0] - expected[:, 0])) > 0.3  # column 0 reacted


def test_react_must_be_a_boolean(tmp_path):
    file = write_track(tmp_path)
    with pytest.raises(ValidationError, match="react"):
        Scenario.model_validate(
            {
                **scenario_with(file, False).model_dump(),
                "obstacles": [{"replay": {"file": str(file), "react": "sometimes"}}],
            }
        )


@needs_data
def test_eth_ucy_react_suite_pairs_with_eth_ucy():
    plain, reactive = generate_suite("eth-ucy", 10, 3), generate_suite("eth-ucy-react", 10, 3)
    for a, b in zip(plain, reactive):
        assert b["name"] == a["name"].replace("eth-ucy-", "eth-ucy-react-")
        assert b["obstacles"][0]["replay"].pop("react") is True
        assert "react" not in a["obstacles"][0]["replay"]
        assert a["obstacles"] == b["obstacles"] and a["path"] == b["path"] and a["robot"] == b["robot"]


@needs_data
def test_real_people_give_way_to_a_robot_at_rest():
    """On real scenes, people walk into a robot standing at its start (``stop``) far less often when they react."""
    plain = generate_suite("eth-ucy", 5, 0)  # one per scene
    reactive = generate_suite("eth-ucy-react", 5, 0)
    hits = {False: 0, True: 0}
    for a, b in zip(plain, reactive):
        hits[False] += run_episode(Scenario.model_validate(a), planner="stop").metrics["collision"]
        hits[True] += run_episode(Scenario.model_validate(b), planner="stop").metrics["collision"]
    assert hits[False] >= 3
    assert hits[True] <= 1


@needs_data
def test_cli_writes_the_reactive_suite_and_the_report_keeps_the_modes_apart(tmp_path):
    from typer.testing import CliRunner

    from viapath.bench.runner import family_of
    from viapath.cli import app
    from viapath.scenarios import load_scenario

    result = CliRunner().invoke(app, ["suite", "eth-ucy-react", "--count", "2", "--seed", "0", "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    files = sorted(tmp_path.glob("*.yaml"))
    assert [f.stem for f in files] == ["eth-ucy-react-eth-0000", "eth-ucy-react-hotel-0001"]
    assert load_scenario(files[0]).obstacles[0].replay.react is True
    assert family_of(files[0].stem) == "eth-ucy-react-eth" != family_of("eth-ucy-eth-0000")


def test_nobody_enters_inside_the_robot(tmp_path):
    # A recording that begins (at 2 s) right where the robot stands, walking away along +x.
    tracks = load_tracks(write_track(tmp_path, start=(0.1, 0.05), rows=20, first_row=5), ROW_S)
    times = episode_times(10.0)
    recorded, _ = replay_states(tracks, times, ROW_S)
    robot = np.zeros((len(times), 2))
    entry = np.flatnonzero(np.isfinite(recorded[:, 0, 0]))[0]
    assert surface_gap(recorded[entry, 0][None], robot[entry][None])[0] < -0.3  # plain: appears inside it
    reactive = ReactiveReplay(tracks, times, 0.0, ROW_S)
    drive(reactive, lambda k: (0.0, 0.0))
    gap = surface_gap(reactive.positions[:, 0], robot)
    assert np.nanmin(gap) >= 0.3 - 1e-9  # enters 0.3 m from it, and no closer afterwards
    np.testing.assert_allclose(
        reactive.positions[entry, 0] / np.hypot(*reactive.positions[entry, 0]),
        np.array([0.1, 0.05]) / np.hypot(0.1, 0.05),
        atol=0.05,
    )  # straight away from the centre
    last = np.flatnonzero(np.isfinite(recorded[:, 0, 0]))[-1]
    assert np.hypot(*(reactive.positions[last, 0] - recorded[last, 0])) < 0.05  # then back on the track
