"""What the tracker reports: a track near the robot from its first detection, one-off clutter farther away only once
confirmed, fragments of a person already tracked never; and the settled velocity (a second filter with little
process noise, restarted when its innovation leaves the gate)."""

import numpy as np
import pytest

from viapath.perception.tracking import MultiTargetTracker, TrackerParams

ROBOT = np.zeros(2)


def test_a_detection_near_the_robot_is_reported_at_once_standing_with_a_walkers_velocity_sigma():
    tracker = MultiTargetTracker()
    tracker.step(0.0, [[1.3, 0.0]], 0.03, 0.25)
    people = tracker.people(ROBOT)
    assert len(people) == 1 and not tracker.confirmed[0]
    assert people.positions[0] == pytest.approx([1.3, 0.0])
    assert people.velocities[0] == pytest.approx([0.0, 0.0])  # standing ...
    assert people.velocity_sigma_mps[0] == pytest.approx(TrackerParams().initial_velocity_sigma_mps)  # ... or walking
    assert len(tracker.people()) == 0  # without the robot's position only confirmed tracks
    # the same track (same id) once confirmed, with a velocity learnt from its detections
    tracker.step(0.1, [[1.2, 0.0]], 0.03, 0.25)
    tracker.step(0.2, [[1.1, 0.0]], 0.03, 0.25)
    assert tracker.confirmed[0] and tracker.people(ROBOT).ids.tolist() == [people.ids[0]]
    assert tracker.people(ROBOT).velocities[0, 0] < -0.5


@pytest.mark.parametrize("distance_m", [1.6, 3.0, 6.0])
def test_one_off_clutter_beyond_the_reporting_distance_is_never_reported(distance_m):
    tracker = MultiTargetTracker()
    tracker.step(0.0, [[0.0, distance_m]], 0.03, 0.1)
    reported = [len(tracker.people(ROBOT))]
    for k in range(1, 6):
        tracker.step(0.1 * k, np.zeros((0, 2)), 0.03, 0.1)
        reported.append(len(tracker.people(ROBOT)))
    assert reported == [0] * 6 and len(tracker) == 0


def test_one_off_clutter_near_the_robot_is_reported_only_while_its_tentative_track_lives():
    params = TrackerParams()
    tracker = MultiTargetTracker(params)
    tracker.step(0.0, [[0.8, 0.5]], 0.03, 0.1)
    reported = [len(tracker.people(ROBOT))]
    for k in range(1, 6):
        tracker.step(0.1 * k, np.zeros((0, 2)), 0.03, 0.1)
        reported.append(len(tracker.people(ROBOT)))
    lives = int(np.floor(params.tentative_max_unseen_s / 0.1 + 1e-9))  # cycles unseen before it is dropped
    assert reported == [1] * (lives + 1) + [0] * (5 - lives)


def test_a_fragment_on_a_confirmed_person_is_not_reported_a_newcomer_beside_them_is():
    tracker = MultiTargetTracker()
    for k in range(3):
        tracker.step(0.1 * k, [[1.0, 0.0]], 0.03, 0.25)
    assert len(tracker.people(ROBOT)) == 1
    # 0.4 m from the person (beyond the spawn exclusion, so a track starts): their discs overlap, a fragment;
    # 0.8 m to the side: clear of them, someone else
    tracker.step(0.3, [[1.0, 0.0], [1.4, 0.0], [1.0, 0.8]], 0.03, 0.25)
    assert len(tracker) == 3
    reported = tracker.people(ROBOT).positions
    assert len(reported) == 2
    assert np.hypot(*(reported - [1.4, 0.0]).T).min() > 0.3
    assert np.hypot(*(reported - [1.0, 0.8]).T).min() < 0.05


def test_reporting_distance_zero_waits_for_confirmation():
    tracker = MultiTargetTracker(TrackerParams(report_tentative_within_m=0.0))
    tracker.step(0.0, [[0.5, 0.0]], 0.03, 0.25)
    tracker.step(0.1, [[0.5, 0.0]], 0.03, 0.25)
    assert len(tracker.people(ROBOT)) == 0
    tracker.step(0.2, [[0.5, 0.0]], 0.03, 0.25)
    assert len(tracker.people(ROBOT)) == 1


def _walk(times_s, turn_at_s=3.0, turn_rate_radps=np.pi / 4):
    """1 m/s along x, from ``turn_at_s`` a turn to +y at ``turn_rate_radps``: positions (exact, by fine
    integration) and velocities at ``times_s``."""
    fine = np.arange(0.0, times_s[-1] + 1e-3, 1e-3)
    heading = np.clip((fine - turn_at_s) * turn_rate_radps, 0.0, np.pi / 2)
    velocity = np.stack([np.cos(heading), np.sin(heading)], axis=1)
    position = np.vstack([[0.0, 0.0], np.cumsum(velocity[:-1], axis=0) * 1e-3])
    index = np.round(times_s / 1e-3).astype(int)
    return position[index], velocity[index]


def _velocity_errors(params: TrackerParams, seed: int):
    times = np.arange(80) * 0.1
    truth, velocity = _walk(times)
    detections = truth + np.random.default_rng(seed).normal(0.0, 0.03, truth.shape)
    tracker = MultiTargetTracker(params)
    errors, sigmas = [], []
    for k, t in enumerate(times):
        tracker.step(t, detections[k : k + 1], 0.03, 0.25)
        assert len(tracker) == 1  # one person, one track, through the turn
        obstacles = tracker.obstacles(confirmed_only=False)
        errors.append(float(np.hypot(*(obstacles.velocities[0] - velocity[k]))))
        sigmas.append(float(obstacles.velocity_sigma_mps[0]))
    return np.array(errors), np.array(sigmas)


def _rms(values):
    return float(np.sqrt(np.mean(np.square(values))))


def test_the_settled_velocity_is_steadier_on_a_straight_walk_and_follows_a_turn():
    # Against the same tracker reporting the agile filter's velocity (the settled filter given the agile's
    # process noise is the agile filter: the same estimates).
    agile = TrackerParams(settled_acceleration_sigma_mps2=TrackerParams().acceleration_sigma_mps2)
    for seed in range(6):
        settled_errors, settled_sigmas = _velocity_errors(TrackerParams(), seed)
        agile_errors, agile_sigmas = _velocity_errors(agile, seed)
        straight, turn, after = slice(10, 30), slice(30, 55), slice(55, 80)  # 1-3 s; 3-5.5 s; 5.5-8 s
        assert _rms(settled_errors[straight]) < 0.5 * _rms(agile_errors[straight])
        assert _rms(settled_errors[after]) < _rms(agile_errors[after])
        # in the turn the settled velocity lags a little more than the agile one, and its σ grows with the gap
        # between the two: it covers its error (2.5 σ) at least as often as the agile σ covers the agile error
        assert _rms(settled_errors[turn]) < 1.5 * _rms(agile_errors[turn])
        covered = np.mean(settled_errors[turn] <= 2.5 * settled_sigmas[turn])
        assert covered >= np.mean(agile_errors[turn] <= 2.5 * agile_sigmas[turn])


def test_a_tentative_track_on_known_static_geometry_waits_for_confirmation():
    # The detector starts tentative tracks on the corners of boxes: one whose disc overlaps geometry the scans
    # showed already is left to its confirmation; one clear of it (a person beside the box) is reported at once.
    from viapath.static import StaticLayer

    box_edge = StaticLayer(np.array([[[1.0, -0.5], [1.0, 0.5]]]))
    tracker = MultiTargetTracker()
    tracker.step(0.0, [[1.1, 0.0], [0.6, 1.0]], 0.03, 0.25)  # 0.1 m from the edge; 0.64 m from its end
    reported = tracker.people(ROBOT, box_edge).positions
    assert reported.tolist() == [[0.6, 1.0]]
    assert len(tracker.people(ROBOT)) == 2  # without the static layer both
    tracker.step(0.1, [[1.1, 0.0], [0.6, 1.0]], 0.03, 0.25)
    tracker.step(0.2, [[1.1, 0.0], [0.6, 1.0]], 0.03, 0.25)
    assert len(tracker.people(ROBOT, box_edge)) == 2  # confirmed: a person, whatever stands near them
