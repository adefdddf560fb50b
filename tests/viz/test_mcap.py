"""MCAP files of runs (issue 14), read back with the ``mcap`` reader, decoded from the schemas stored
in the file: channels and schema names, one message per cycle per topic, log times = simulated
time, robot poses = the trace, scans = what the scanners read, x-y-t cylinders where the forecast
puts them. Runs: the paper's front case (oracle), the side case with laser perception, and
replayed ETH/UCY people."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("foxglove", reason="needs the viz extra (foxglove-sdk)")
mcap_reader = pytest.importorskip("mcap.reader", reason="needs the viz extra (mcap)")
protobuf_decoder = pytest.importorskip("mcap_protobuf.decoder", reason="needs the viz extra (mcap-protobuf-support)")

from typer.testing import CliRunner  # noqa: E402

from viapath.bench.suites import data_root  # noqa: E402
from viapath.cli import app  # noqa: E402
from viapath.scenarios import load_scenario, scenario_from_dict  # noqa: E402
from viapath.sim.loop import run_episode  # noqa: E402
from viapath.sim.obstacles import scenario_obstacle_states  # noqa: E402
from viapath.viz.foxglove import Views  # noqa: E402
from viapath.viz.scene import ForecastSettings  # noqa: E402

# The topics issue 14 lists, with Foxglove's schema names (and ours for the two JSON channels).
COMMON = {
    "/tf": "foxglove.FrameTransforms",
    "/robot/footprint": "foxglove.SceneUpdate",
    "/perception/tracks": "foxglove.SceneUpdate",
    "/path": "foxglove.SceneUpdate",
    "/world/static": "foxglove.SceneUpdate",
    "/plan/candidates": "foxglove.SceneUpdate",
    "/plan/chosen": "foxglove.SceneUpdate",
    "/plan/costs": "viapath.PlanCosts",
    "/xyt": "foxglove.SceneUpdate",
    "/metrics": "viapath.Metrics",
}
LASER = {
    "/scan/front": "foxglove.LaserScan",
    "/scan/rear": "foxglove.LaserScan",
    "/perception/blind_sectors": "foxglove.SceneUpdate",
    "/perception/detections": "foxglove.SceneUpdate",
}
SCALE = ForecastSettings().time_scale_m_per_s
ETH_UCY = data_root() / "eth_ucy_trajectron"


def _record(scenario, file: Path, **kwargs):
    """Run with the MCAP view and keep, beside it, what the loop handed out (independent of the file)."""
    kept = []
    with Views(scenario, kwargs.pop("planner", scenario.planner.name), mcap=file) as views:

        def on_step(record):
            kept.append(
                {
                    "time_s": record.time_s,
                    "world": record.world,
                    "scans": None if record.scans is None else [np.array(s) for s in record.scans],
                    "tracks": record.observation.obstacles,
                }
            )
            views.on_step(record)

        episode = run_episode(scenario, planner_overrides=views.planner_overrides, on_step=on_step, **kwargs)
    return episode, kept


def _decoded(file: Path, topic: str) -> list:
    with open(file, "rb") as handle:
        reader = mcap_reader.make_reader(handle, decoder_factories=[protobuf_decoder.DecoderFactory()])
        return [(message.log_time, decoded) for _, _, message, decoded in reader.iter_decoded_messages(topics=[topic])]


@pytest.fixture(scope="module")
def front(tmp_path_factory):
    file = tmp_path_factory.mktemp("mcap") / "front.mcap"
    scenario = load_scenario("paper-front")
    episode, kept = _record(scenario, file, perception="oracle", seed=0, position_noise_m=0.0, velocity_noise_mps=0.0)
    return scenario, episode, kept, file


@pytest.fixture(scope="module")
def side_laser(tmp_path_factory):
    file = tmp_path_factory.mktemp("mcap") / "side.mcap"
    scenario = load_scenario("paper-side")
    episode, kept = _record(scenario, file, perception="laser", seed=1)
    return scenario, episode, kept, file


def _channels(file: Path) -> dict[str, tuple[str, int]]:
    with open(file, "rb") as handle:
        summary = mcap_reader.make_reader(handle).get_summary()
    counts = summary.statistics.channel_message_counts
    return {c.topic: (summary.schemas[c.schema_id].name, counts.get(cid, 0)) for cid, c in summary.channels.items()}


@pytest.mark.parametrize("case, topics", [("front", COMMON), ("side_laser", {**COMMON, **LASER})])
def test_channels_schemas_and_one_message_per_cycle(request, case, topics):
    _, episode, kept, file = request.getfixturevalue(case)
    cycles = len(episode.trace.times_s) - 1  # the last row of a trace has no planning cycle
    assert len(kept) == cycles
    channels = _channels(file)
    assert {topic: schema for topic, (schema, _) in channels.items()} == topics
    assert {topic: count for topic, (_, count) in channels.items()} == dict.fromkeys(topics, cycles)


def test_log_times_are_simulated_time_and_poses_are_the_trace(front):
    _, episode, _, file = front
    trace = episode.trace
    expected_ns = np.round(trace.times_s[:-1] * 1e9).astype(np.int64)
    for topic in COMMON:
        with open(file, "rb") as handle:
            times = [m.log_time for _, _, m in mcap_reader.make_reader(handle).iter_messages(topics=[topic])]
        np.testing.assert_array_equal(times, expected_ns)
    poses = []
    for log_time, message in _decoded(file, "/tf"):
        base = next(t for t in message.transforms if t.child_frame_id == "base")
        assert base.parent_frame_id == "world"
        assert base.timestamp.seconds * 10**9 + base.timestamp.nanos == log_time
        q = base.rotation
        poses.append((base.translation.x, base.translation.y, 2.0 * math.atan2(q.z, q.w)))
    poses = np.array(poses)
    np.testing.assert_allclose(poses[:, :2], trace.robot_poses[:-1, :2], atol=1e-9)
    heading_error = np.angle(np.exp(1j * (poses[:, 2] - trace.robot_poses[:-1, 2])))
    np.testing.assert_allclose(heading_error, 0.0, atol=1e-9)


def _check_cylinders(file: Path, expected_centre, expected_radius, min_checked: int) -> int:
    """Every vertex of every person's x-y-t mesh lies at the expected radius from the expected
    centre at its height's time (or is a cap's centre). Returns how many meshes were checked."""
    checked = 0
    for step, (_, update) in enumerate(_decoded(file, "/xyt")):
        for entity in update.entities:
            if not entity.id.startswith("person-"):
                continue
            assert entity.frame_id == "xyt"
            person = int(entity.id.split("-", 1)[1])
            vertices = np.array([(p.x, p.y, p.z) for p in entity.triangles[0].points])
            t = vertices[:, 2] / SCALE
            centre = expected_centre(step, person, t)
            distance = np.hypot(*(vertices[:, :2] - centre).T)
            on_surface = np.abs(distance - expected_radius(step, person)) < 1e-6
            at_cap_centre = distance < 1e-6
            assert np.all(on_surface | at_cap_centre), (step, person)
            assert on_surface.sum() > 0.5 * len(vertices)
            assert t.min() == pytest.approx(0.0) and t.max() == pytest.approx(ForecastSettings().horizon_s)
            checked += 1
    assert checked >= min_checked
    return checked


def test_xyt_cylinders_are_where_the_true_future_puts_the_person(front):
    """paper-front: the person walks at constant velocity and is perceived exactly, so the cylinder's
    centre at height t is where the scenario's motion model puts the person t seconds later."""
    scenario, _episode, kept, file = front
    robot_radius = scenario.robot.radius

    def centre(step, person, t):
        positions, _, _ = scenario_obstacle_states(scenario, kept[step]["time_s"] + t)
        return positions[:, person]

    def radius(step, person):
        return kept[step]["world"].obstacle_radii_m[person] + robot_radius

    _check_cylinders(file, centre, radius, min_checked=50)


def test_plan_candidates_costs_and_chosen(front):
    _, _, _, file = front
    with open(file, "rb") as handle:
        costs = [
            json.loads(m.data) for _, _, m in mcap_reader.make_reader(handle).iter_messages(topics=["/plan/costs"])
        ]
    candidates = _decoded(file, "/plan/candidates")
    chosen = _decoded(file, "/plan/chosen")
    avoiding = [i for i, c in enumerate(costs) if c["status"] == "avoid" and c["runner_up"] is not None]
    assert avoiding, "paper-front passes the person: some cycles must weigh several candidates"
    for i in avoiding:
        entry = costs[i]
        assert entry["chosen"]["E"] is not None and entry["runner_up"]["E"] >= entry["chosen"]["E"] - 0.2
        # One line per candidate, all starting at the robot; the chosen line passes its via points.
        lines = candidates[i][1].entities[0].lines
        assert len(lines) == entry["candidate_count"] > 1
        chosen_entity = chosen[i][1].entities[0]
        line = np.array([(p.x, p.y) for p in chosen_entity.lines[0].points])
        for sphere in chosen_entity.spheres:
            via = np.array([sphere.pose.position.x, sphere.pose.position.y])
            assert np.min(np.hypot(*(line - via).T)) < 1e-9
    # Each critic's share of E (Eq. 1 term by term, plus side and hysteresis) adds up to E.
    for i in avoiding:
        entry = costs[i]
        assert entry["terms_available"]
        terms = {k: v for k, v in entry["chosen"]["terms"].items() if k != "total"}
        assert {"distance", "time", "speed", "heading"} <= set(terms)
        assert abs(sum(terms.values()) - entry["chosen"]["E"]) < 1e-9


def test_laser_scans_are_what_the_scanners_read(side_laser):
    _, _, kept, file = side_laser
    for name, index in (("front", 0), ("rear", 1)):
        scans = _decoded(file, f"/scan/{name}")
        assert len(scans) == len(kept)
        with_hits = 0
        for step in range(0, len(kept), 5):
            message = scans[step][1]
            assert message.frame_id == f"laser_{name}"
            raw = kept[step]["scans"][index]
            sent = np.array(message.ranges)
            assert len(sent) == len(raw) == 683
            valid = np.isfinite(raw) & (raw > 0)
            with_hits += bool(valid.any())
            np.testing.assert_allclose(sent[valid], raw[valid], rtol=1e-6)  # float32 on the wire
            assert np.all(np.isnan(sent[~valid]))
            # URG-04LX (docs/design.md §3): 683 beams 360°/1024 apart, i.e. 239.8° from first to last beam.
            assert message.end_angle - message.start_angle == pytest.approx(682 * 2 * np.pi / 1024, abs=1e-9)
        assert with_hits >= 5  # the person is in view of each scanner for a while
    tf = _decoded(file, "/tf")[0][1]
    mounts = {t.child_frame_id: t for t in tf.transforms if t.parent_frame_id == "base"}
    assert mounts["laser_front"].translation.x == pytest.approx(0.145)
    assert mounts["laser_rear"].translation.x == pytest.approx(-0.145)
    rear_yaw = 2.0 * math.atan2(mounts["laser_rear"].rotation.z, mounts["laser_rear"].rotation.w)
    assert abs(np.angle(np.exp(1j * (rear_yaw - math.pi)))) < 1e-9


def test_laser_tracks_are_what_the_planner_was_told(side_laser):
    _, _, kept, file = side_laser
    updates = _decoded(file, "/perception/tracks")
    seen = 0
    for step, (_, update) in enumerate(updates):
        tracks = kept[step]["tracks"]
        assert len(update.entities) == len(tracks)
        for entity in update.entities:
            track = int(entity.id.split("-", 1)[1])
            row = int(np.flatnonzero(tracks.ids == track)[0])
            position = entity.cylinders[0].pose.position
            assert (position.x, position.y) == pytest.approx(tuple(tracks.positions[row]), abs=1e-9)
            seen += 1
    assert seen > 50  # the crossing person is tracked for most of the run


@pytest.mark.skipif(not ETH_UCY.is_dir(), reason=f"ETH/UCY data not found at {ETH_UCY} (set VIAPATH_DATA)")
def test_replayed_people_cylinders_follow_their_reported_velocity(tmp_path):
    """Replayed ETH/UCY people do not walk straight, so the check is against the forecast the planner
    was given: centre = reported position + reported velocity · t (oracle, no noise)."""
    data = {
        "name": "zara01-mcap",
        "dt_s": 0.1,
        "duration_s": 8.0,
        "robot": {"start": [3.0, 5.0], "heading": 0.0, "speed": 0.3, "radius": 0.25},
        "path": {"waypoints": [[3.0, 5.0], [12.0, 5.0]], "half_width": 1.5},
        "obstacles": [
            {
                "replay": {
                    "file": str(ETH_UCY / "crowds_zara01.txt"),
                    "dt_s": 0.4,
                    "start_s": 120,
                    "offset": [0, 0],
                    "radius": 0.25,
                }
            }
        ],
    }
    scenario = scenario_from_dict(data)
    file = tmp_path / "zara.mcap"
    episode, kept = _record(scenario, file, perception="oracle", seed=0, position_noise_m=0.0, velocity_noise_mps=0.0)
    cycles = len(episode.trace.times_s) - 1
    assert {topic: count for topic, (_, count) in _channels(file).items()} == dict.fromkeys(COMMON, cycles)

    def centre(step, person, t):
        world = kept[step]["world"]
        return world.obstacle_positions[person] + t[:, None] * world.obstacle_velocities[person]

    def radius(step, person):
        return kept[step]["world"].obstacle_radii_m[person] + scenario.robot.radius

    checked = _check_cylinders(file, centre, radius, min_checked=cycles)
    # Every person present in a cycle has a cylinder in it.
    present = sum(int(np.isfinite(k["world"].obstacle_positions).all(axis=1).sum()) for k in kept)
    assert checked == present


def test_cli_writes_mcap_and_refuses_bad_paths(tmp_path):
    file = tmp_path / "run.mcap"
    runner = CliRunner()
    result = runner.invoke(app, ["run", "paper-behind", "--mcap", str(file), "--json"])
    assert result.exit_code == 0, result.output
    metrics = json.loads(result.stdout.strip().splitlines()[-1])
    assert metrics["reached_goal"]
    assert file.stat().st_size > 0 and "/xyt" in _channels(file)
    size = file.stat().st_size
    # An existing file without --force: refused before the run, the file untouched.
    again = runner.invoke(app, ["run", "paper-behind", "--mcap", str(file)])
    assert again.exit_code == 2 and "--force" in again.output and "Traceback" not in again.output
    assert file.stat().st_size == size
    forced = runner.invoke(app, ["run", "paper-behind", "--mcap", str(file), "--force", "--json"])
    assert forced.exit_code == 0, forced.output
    (tmp_path / "a.mcap").mkdir()
    for bad, words in (
        (tmp_path / "missing" / "run.mcap", "does not exist"),
        (tmp_path / "run.txt", ".mcap"),
        (Path("/proc/run.mcap"), "cannot write"),
        (tmp_path / "a.mcap", "is a folder"),
    ):
        result = runner.invoke(app, ["run", "paper-behind", "--mcap", str(bad)])
        assert result.exit_code == 2, (bad, result.output)
        assert words in result.output and "Traceback" not in result.output
    assert not (tmp_path / "run.txt").exists()
    assert runner.invoke(app, ["run", "paper-behind", "--rate", "4"]).exit_code == 2


def test_static_layer_is_drawn_as_the_planner_was_told(tmp_path):
    """A box and a wall: each cycle's /world/static line list holds exactly the segments of the observation."""
    from viapath.scenarios.loader import scenario_from_dict

    scenario = scenario_from_dict(
        {
            "name": "box",
            "robot": {"start": [0.0, 0.0], "heading": 0.0, "speed": 0.4, "radius": 0.25},
            "path": {"waypoints": [[0.0, 0.0], [4.0, 0.0]], "half_width": 1.0},
            "duration_s": 3.0,
            "boxes": [{"center": [2.0, 0.0], "size": [0.5, 0.5]}],
            "walls": [[[0.0, 1.3], [4.0, 1.3]]],
        }
    )
    file = tmp_path / "static.mcap"
    _episode, kept = _record(scenario, file)
    updates = _decoded(file, "/world/static")
    assert len(updates) == len(kept) > 0
    expected = np.concatenate([scenario.static_shapes()[k][0] for k in range(2)]).reshape(-1, 2)
    for _, update in updates:
        (entity,) = update.entities
        points = np.array([[p.x, p.y] for p in entity.lines[0].points])
        assert np.allclose(np.sort(points, axis=0), np.sort(expected, axis=0))
