"""Assignment, Kalman tracking, M-of-N confirmation and deletion, LaserPerception end to end."""

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from viapath.observation import Obstacles
from viapath.perception.assignment import gated_assignment, linear_sum_assignment
from viapath.perception.laser import LaserPerception, tracking_errors
from viapath.perception.tracking import MultiTargetTracker, TrackerParams
from viapath.sim.perception import WorldSnapshot


def brute_force_assignment(cost) -> tuple[np.ndarray, np.ndarray]:
    """The oracle: every matching of the smaller side tried."""
    cost = np.asarray(cost, dtype=float)
    transposed = cost.shape[0] > cost.shape[1]
    c = cost.T if transposed else cost
    n, m = c.shape
    best, best_cols = np.inf, None
    for cols in itertools.permutations(range(m), n):
        total = c[np.arange(n), cols].sum()
        if total < best:
            best, best_cols = total, cols
    if best_cols is None or not np.isfinite(best):
        raise ValueError("cost matrix is infeasible")
    rows, cols = np.arange(n), np.array(best_cols, dtype=int)
    if transposed:
        order = np.argsort(cols)
        return cols[order], rows[order]
    return rows, cols


@settings(max_examples=60, deadline=None, derandomize=True)
@given(
    st.integers(1, 5).flatmap(
        lambda n: st.integers(1, 5).flatmap(
            lambda m: arrays(float, (n, m), elements=st.floats(0, 100, allow_nan=False))
        )
    )
)
def test_hungarian_matches_brute_force(cost):
    rows, cols = linear_sum_assignment(cost)
    ref_rows, ref_cols = brute_force_assignment(cost)
    assert len(rows) == min(cost.shape) == len(set(cols.tolist()))
    assert cost[rows, cols].sum() == pytest.approx(cost[ref_rows, ref_cols].sum(), abs=1e-9)


def test_gated_assignment_leaves_far_pairs_unmatched():
    cost = np.array([[1.0, 50.0], [2.0, 50.0]])
    assert gated_assignment(cost, gate=9.21) == [(0, 0)]
    # competing tracks: the optimum is not the greedy choice
    cost = np.array([[1.0, 2.0], [1.5, 8.0]])
    assert gated_assignment(cost, gate=9.21) == [(0, 1), (1, 0)]
    assert gated_assignment(np.full((2, 2), np.inf), gate=9.21) == []


def walker_measurements(rng, speed=1.0, heading=0.4, n=60, dt=0.1, sigma=0.03):
    v = speed * np.array([np.cos(heading), np.sin(heading)])
    t = np.arange(n) * dt
    truth = np.array([1.0, -2.0]) + t[:, None] * v
    return t, truth, v, truth + rng.normal(0, sigma, truth.shape)


def test_velocity_of_a_synthetic_walker_after_one_second():
    errors = []
    for seed in range(30):
        rng = np.random.default_rng(seed)
        t, _truth, v, z = walker_measurements(rng)
        tracker = MultiTargetTracker()
        for k in range(len(t)):
            tracker.step(t[k], z[k : k + 1], 0.03, 0.25)
            if k >= 10:  # after 1 s of tracking
                obstacles = tracker.obstacles()
                assert len(obstacles) == 1
                errors.append(np.hypot(*(obstacles.velocities[0] - v)))
    rmse = float(np.sqrt(np.mean(np.square(errors))))
    assert rmse < 0.12  # docs/design.md §3 expects ±0.03–0.1 m/s after ~1 s
    assert rmse > 0.005  # noise really is in the loop


def test_crossing_walkers_keep_their_identities():
    rng = np.random.default_rng(1)
    tracker = MultiTargetTracker()
    dt = 0.1
    ids_a, ids_b = set(), set()
    for k in range(60):
        t = k * dt
        a = np.array([-3.0 + 1.0 * t, -0.1 + 0.0 * t])  # walking +x
        b = np.array([3.0 - 1.0 * t, 0.1])  # walking -x, passes 0.2 m from a at t = 3 s
        z = np.stack([a, b]) + rng.normal(0, 0.02, (2, 2))
        tracker.step(t, z[::-1] if k % 2 else z, 0.02, 0.25)  # detection order must not matter
        obs = tracker.obstacles()
        if k >= 5:
            assert len(obs) == 2
            ia = obs.ids[np.argmin(np.hypot(*(obs.positions - a).T))]
            ib = obs.ids[np.argmin(np.hypot(*(obs.positions - b).T))]
            ids_a.add(int(ia))
            ids_b.add(int(ib))
    assert len(ids_a) == 1 and len(ids_b) == 1 and ids_a != ids_b
    final = tracker.obstacles()
    vx = dict(zip(final.ids.tolist(), final.velocities[:, 0]))
    assert vx[ids_a.pop()] == pytest.approx(1.0, abs=0.15)
    assert vx[ids_b.pop()] == pytest.approx(-1.0, abs=0.15)


def test_confirmation_m_of_n_and_deletion_after_unseen_time():
    tracker = MultiTargetTracker(TrackerParams(confirm_hits=3, confirm_window=5, max_unseen_s=1.0))
    p = np.array([[2.0, 0.0]])
    tracker.step(0.0, p, 0.02, 0.25)
    tracker.step(0.1, p, 0.02, 0.25)
    assert len(tracker.obstacles()) == 0 and len(tracker) == 1  # 2 hits: tentative
    tracker.step(0.2, p, 0.02, 0.25)
    assert len(tracker.obstacles()) == 1  # 3 of 3: confirmed
    for k in range(3, 13):  # unseen for 1.0 s: still coasting
        tracker.step(k * 0.1, np.zeros((0, 2)), 0.02, 0.25)
    assert len(tracker.obstacles()) == 1
    sigma_coasting = tracker.obstacles().position_sigma_m[0]
    tracker.step(1.3, np.zeros((0, 2)), 0.02, 0.25)
    assert len(tracker) == 0
    assert sigma_coasting > 0.05  # the covariance grew while coasting


def test_a_single_clutter_hit_never_becomes_a_track():
    tracker = MultiTargetTracker()
    tracker.step(0.0, [[1.0, 1.0]], 0.02, 0.1)
    for k in range(1, 6):
        tracker.step(k * 0.1, np.zeros((0, 2)), 0.02, 0.1)
    assert len(tracker) == 0


def snapshot(t, pose, positions, velocities, radius=0.25, walls=None):
    positions = np.asarray(positions, float)
    return WorldSnapshot(
        t,
        np.asarray(pose, float),
        0.25,
        positions,
        np.asarray(velocities, float),
        np.full(len(positions), radius),
        np.zeros((0, 2, 2)) if walls is None else np.asarray(walls, float),
    )


def run(perception, frames):
    reported = [perception.observe(w) for w in frames]
    return reported, tracking_errors(reported, frames)


def test_laser_perception_tracks_obstacles_around_a_moving_robot():
    """Obstacles in front, behind and beside a robot driving at 0.3 m/s and turning: world-frame tracks."""
    walls = [[[-3, -3], [9, -3]], [[-3, 3], [9, 3]]]
    frames = []
    for k in range(80):
        t = k * 0.1
        pose = (0.3 * t, 0.2 * np.sin(0.5 * t), 0.1 * np.cos(0.5 * t))
        obstacles = [[5.0 - 0.3 * t, 0.6], [-2.0 + 0.5 * t, -1.0], [1.5, 2.0 - 0.3 * t], [np.nan, np.nan]]
        velocities = [[-0.3, 0.0], [0.5, 0.0], [0.0, -0.3], [0.0, 0.0]]
        frames.append(snapshot(t, pose, obstacles, velocities, walls=walls))
    perception = LaserPerception()
    perception.reset(np.random.default_rng(5))
    reported, errors = run(perception, frames)
    assert all(len(r) == 3 for r in reported[10:])
    assert errors["false_track_samples"] == 0
    assert errors["track_position_rmse_m"] < 0.05
    assert errors["track_velocity_rmse_mps"] < 0.1
    assert len(perception.last_points_world) > 100
    assert perception.blind_polygon_world().shape[1] == 2
    # the scan points really are world frame: they lie on the walls or on the obstacles
    last = frames[-1]
    on_wall = np.abs(np.abs(perception.last_points_world[:, 1]) - 3.0) < 0.15
    present = last.obstacle_positions[:3]
    on_obstacle = np.hypot(*(perception.last_points_world[:, None, :] - present[None]).transpose(2, 0, 1)).min(1) < 0.4
    assert (on_wall | on_obstacle).all()


def test_same_seed_same_tracks_and_the_retired_ray_option_changes_nothing():
    frames = [snapshot(k * 0.1, (0, 0, 0), [[2.0 - 0.2 * k * 0.1, 0.5]], [[-0.2, 0.0]]) for k in range(20)]
    a = LaserPerception()
    with pytest.warns(FutureWarning, match="'ray_compute' no longer does anything"):
        b = LaserPerception(ray_compute="auto")
    with pytest.raises(TypeError, match="ray_colour"):
        LaserPerception(ray_colour="red")
    a.reset(np.random.default_rng(3))
    b.reset(np.random.default_rng(3))
    ra, _ = run(a, frames)
    rb, _ = run(b, frames)
    for x, y in zip(ra, rb):
        np.testing.assert_array_equal(x.positions, y.positions)


def test_options_are_checked():
    with pytest.raises(ValueError, match="unknown option"):
        LaserPerception(tracker={"confirm_hit": 3})
    with pytest.raises(ValueError, match="oracle option"):
        LaserPerception(position_noise_m=0.05)
    p = LaserPerception(
        scanners=[{"name": "front", "beam_count": 513}], tracker={"confirm_hits": 2}, fixed_radius_m=0.3
    )
    assert p.scanners[0].beam_count == 513 and p.detector_params.fixed_radius_m == 0.3
    assert len(p.blind_sectors) >= 1  # one 180° scanner leaves the back unseen


def test_tracking_errors_nearest_truth_and_false_tracks():
    world = snapshot(0.0, (0, 0, 0), [[1.0, 0.0], [5.0, 5.0], [np.nan, np.nan]], [[1.0, 0.0], [0, 0], [0, 0]])
    reported = Obstacles(np.array([[1.1, 0.0], [9.0, 9.0]]), np.array([[0.8, 0.0], [0, 0]]), np.full(2, 0.25))
    errors = tracking_errors([reported], [world])
    assert errors["track_position_rmse_m"] == pytest.approx(0.1)
    assert errors["track_velocity_rmse_mps"] == pytest.approx(0.2)
    assert errors["false_track_samples"] == 1
    assert np.isnan(tracking_errors([Obstacles.empty()], [world])["track_position_rmse_m"])


def test_scans_command_error_keeps_brackets_of_the_install_hint(monkeypatch):
    """Rich markup must not eat "[ros]" in "pip install 'viapath[ros]'" (the error is one plain line)."""
    import typer
    from typer.testing import CliRunner

    import viapath.io.rosbag as rosbag
    from viapath.cli.scans import scans as scans_command

    def missing():
        raise rosbag.RosbagsMissingError(
            "reading ROS bags needs the 'rosbags' package; install it with: pip install 'viapath[ros]'"
        )

    monkeypatch.setattr(rosbag, "_anyreader", missing)
    app = typer.Typer()

    @app.command()
    def noop() -> None:
        pass

    app.command("scans")(scans_command)
    result = CliRunner().invoke(app, ["scans", __file__])
    assert result.exit_code == 2
    assert "viapath[ros]" in result.output and "Traceback" not in result.output


# -- standing still: static tracks ----------------------------------------------------------------


def _run_tracker(tracker, positions_at, times_s, sigma_m=0.02, seed=0):
    """Feed one noisy detection per cycle at ``positions_at(t)``; returns per cycle (people, all confirmed, explaining)."""
    rng = np.random.default_rng(seed)
    out = []
    for t in times_s:
        z = np.asarray(positions_at(t), dtype=float) + rng.normal(0.0, sigma_m, 2)
        tracker.step(t, z[None, :], sigma_m, 0.25)
        out.append((len(tracker.people()), len(tracker.obstacles()), len(tracker.explaining()[0])))
    return out


def test_a_track_standing_still_becomes_static_and_stops_explaining_its_returns():
    params = TrackerParams()
    tracker = MultiTargetTracker(params)
    times = np.arange(0.0, 6.0, 0.1)
    out = _run_tracker(tracker, lambda t: (2.0, 1.0), times)
    people = np.array([o[0] for o in out])
    confirmed = np.array([o[1] for o in out])
    explaining = np.array([o[2] for o in out])
    assert (confirmed[5:] == 1).all()  # still reported by obstacles() (what the scans command lists)
    assert people[-1] == 0 and explaining[-1] == 0, out[-5:]
    # Static no earlier than static_after_s after it stopped (born at t = 0) and not much later either,
    # and it stays static while it stands.
    first_static = times[5:][people[5:] == 0][0]
    assert params.static_after_s - 1e-9 <= first_static <= params.static_after_s + 1.0, first_static
    assert (people[times >= first_static] == 0).all() and (explaining[times >= first_static] == 0).all()


def test_a_static_track_that_starts_walking_is_a_person_again_within_half_a_second():
    tracker = MultiTargetTracker(TrackerParams())
    start_s = 5.0
    accel = 1.0  # a person starting at 1 m/s² from rest, away along x

    def position(t):
        dt = max(t - start_s, 0.0)
        return (2.0 + 0.5 * accel * min(dt, 1.0) ** 2 + max(dt - 1.0, 0.0) * accel, 1.0)

    times = np.arange(0.0, 8.0, 0.1)
    out = _run_tracker(tracker, position, times, seed=3)
    people = np.array([o[0] for o in out])
    assert people[times.searchsorted(start_s - 0.05)] == 0  # static before it moves
    walking = times[(times > start_s) & (people == 1)]
    assert len(walking) and walking[0] - start_s <= 0.5 + 1e-9, walking[:3]
    assert (people[times > start_s + 0.5] == 1).all()  # and stays a person while it walks


def test_a_walker_and_a_slow_walker_never_become_static():
    for speed in (1.0, 0.15):
        tracker = MultiTargetTracker(TrackerParams())
        out = _run_tracker(tracker, lambda t, v=speed: (v * t, 0.0), np.arange(0.0, 10.0, 0.1), seed=1)
        assert all(o[0] == 1 for o in out[5:]), (speed, [o for o in out if o[0] != 1][:3])


def test_static_after_inf_keeps_every_track_a_person():
    tracker = MultiTargetTracker(TrackerParams(static_after_s=float("inf")))
    out = _run_tracker(tracker, lambda t: (2.0, 1.0), np.arange(0.0, 10.0, 0.1))
    assert all(o[0] == 1 and o[2] == 1 for o in out[5:])
    with pytest.raises(ValueError, match="static_after_s"):
        TrackerParams(static_after_s=0.0)
