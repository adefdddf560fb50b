"""When is a person first seen? One definition (viapath.sim.metrics.first_seen_steps) for the simulator
(the perception is handed the person, with the velocity they walk at, in that cycle), the metrics
(appearance) and the avoidable search (which starts there); and the robot reacts in that cycle."""

import numpy as np
import pytest

from viapath.bench.avoidable import judge, make_world
from viapath.io.eth_ucy import load_tracks, replay_states
from viapath.observation import MotionLimits
from viapath.scenarios import scenario_from_dict
from viapath.sim.loop import run_episode
from viapath.sim.metrics import appeared_in_step, first_seen_steps, overlap_on_appearance

ROW_S = 0.4


@pytest.fixture
def walker_file(tmp_path):
    """A person first recorded at scene time 2.0 s at x = 1.9 m, walking at -1.7 m/s along x (the real
    pedestrian the issue describes: 1.3 m ahead of a robot at 0.3 m/s, straight at it), then one standing
    in the robot's way from 6 s (to test the appearance of someone already overlapping the robot)."""
    rows = [f"{50 + 10 * i}\t1\t{1.9 - 1.7 * ROW_S * i:.4f}\t0.1" for i in range(12)]
    file = tmp_path / "walker.txt"
    file.write_text("\n".join(rows) + "\n")
    return file


def _scenario(file, **robot):
    return scenario_from_dict(
        {
            "name": "appears-close",
            "dt_s": 0.1,
            "duration_s": 6.0,
            "robot": {"start": [0, 0], "heading": 0, "radius": 0.25, "speed": 0.3, **robot},
            "path": {"waypoints": [[0, 0], [8, 0]], "half_width": 1.0},
            "obstacles": [{"replay": {"file": str(file), "dt_s": ROW_S, "radius": 0.25}}],
        },
        "appears-close",
    )


def test_a_replayed_person_has_the_velocity_of_their_first_interval_at_their_first_sample(walker_file):
    tracks = load_tracks(walker_file, ROW_S)
    times = np.array([1.9, 2.0, 2.1, 2.4, 2.5])
    positions, velocities = replay_states(tracks, times, ROW_S)
    assert np.isnan(positions[0]).all() and np.isnan(velocities[0]).all()
    assert velocities[1:, 0] == pytest.approx(np.tile([-1.7, 0.0], (4, 1)))


def test_simulator_metric_and_search_agree_on_the_first_cycle_a_person_is_seen(walker_file):
    # The path-following baseline drives on into the person: an at-fault contact for the search to judge.
    episode = run_episode(_scenario(walker_file), planner="follow", shield=False, record_perceived=True)
    trace = episode.trace
    first = int(first_seen_steps(trace.obstacle_positions)[0])
    assert first == 20  # 2.0 s
    # the simulator: the first cycle the perception hands over the person, with the velocity of their
    # motion over that step
    handed = [k for k, seen in enumerate(trace.perceived) if 0 in seen.ids]
    assert handed[0] == first
    motion = (trace.obstacle_positions[first + 1, 0] - trace.obstacle_positions[first, 0]) / trace.dt_s
    assert trace.perceived[first].velocities[0] == pytest.approx(motion, abs=1e-9)
    # the metrics: the person appears in that step
    assert np.flatnonzero(appeared_in_step(trace.obstacle_positions)[:, 0]).tolist() == [first]
    assert np.flatnonzero(make_world(trace, MotionLimits()).appeared[:, 0]).tolist() == [first]
    # the search: it starts from the robot's state in that step
    assert episode.metrics["at_fault_collision"]
    (verdict,) = judge(trace, MotionLimits())
    assert round(verdict.appeared_s / trace.dt_s) == first
    assert verdict.robot_speed_at_appearance_mps == pytest.approx(trace.robot_speeds_mps[first])


def test_someone_appearing_on_the_robot_is_exempt_in_the_step_they_are_first_seen(walker_file):
    # the path follower at 0.3 m/s is 0.6 m on, where the person's first sample is, when they appear
    episode = run_episode(_scenario(walker_file, start=[1.3, 0.1]), planner="follow", shield=False)
    overlap = overlap_on_appearance(episode.trace)
    assert np.flatnonzero(overlap[:, 0]).tolist() == [int(first_seen_steps(episode.trace.obstacle_positions)[0])]


def test_the_robot_brakes_in_the_cycle_the_person_is_first_seen(walker_file):
    episode = run_episode(_scenario(walker_file))
    trace = episode.trace
    first = int(first_seen_steps(trace.obstacle_positions)[0])
    assert trace.commands[first - 1, 0] == pytest.approx(0.3)  # straight on at the nominal speed before
    assert trace.commands[first, 0] < trace.robot_speeds_mps[first] - 0.1  # slowing in that very cycle
    assert not episode.metrics["at_fault_collision"]


@pytest.mark.parametrize("perception", ["tracked", "laser"])
def test_through_a_tracker_the_robot_brakes_in_the_cycle_the_person_is_first_seen(walker_file, perception):
    # The tracker reports a track near the robot on its first detection (standing, velocity σ 1 m/s: a person who
    # may walk any way), without waiting for the confirmation two cycles later.
    noise = {"position_noise_m": 0.03} if perception == "tracked" else {}
    episode = run_episode(_scenario(walker_file), perception=perception, record_perceived=True, **noise)
    trace = episode.trace
    first = int(first_seen_steps(trace.obstacle_positions)[0])
    assert len(trace.perceived[first - 1]) == 0 and len(trace.perceived[first]) == 1  # reported in that cycle
    assert trace.perceived[first].velocity_sigma_mps[0] == pytest.approx(1.0)
    assert trace.commands[first - 1, 0] == pytest.approx(0.3)
    assert trace.commands[first, 0] < trace.robot_speeds_mps[first] - 0.1  # slowing in that very cycle
    assert not episode.metrics["at_fault_collision"]
