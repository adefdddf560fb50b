"""Reading LaserScans from ROS 1 / ROS 2 (sqlite3, MCAP) bags, the real leg_tracker recordings, `viapath scans`."""

import json
import os
from pathlib import Path

import numpy as np
import pytest

rosbags = pytest.importorskip("rosbags", reason="rosbags not installed (pip install 'viapath[ros]')")

from viapath.io.rosbag import BagError, read_laser_scans, read_pose_arrays  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
DATA = Path(os.environ.get("VIAPATH_DATA", REPO.parent / "shared" / "data")) / "leg_tracker_laser"
POSITIVE = DATA / "positive_2_extracted.bag"
DEMO = DATA / "demo_stationary_simple_environment.bag"
needs_data = pytest.mark.skipif(
    not POSITIVE.exists() or not DEMO.exists(), reason=f"leg_tracker bags not found in {DATA} (set VIAPATH_DATA)"
)


def laser_messages(typestore, n=5):
    LaserScan = typestore.types["sensor_msgs/msg/LaserScan"]
    Header = typestore.types["std_msgs/msg/Header"]
    Time = typestore.types["builtin_interfaces/msg/Time"]
    out = []
    for k in range(n):
        ranges = np.full(181, np.inf, dtype=np.float32)
        ranges[80:101] = 2.0 - 0.01 * k
        ranges[10] = 0.0
        ranges[11] = np.nan
        out.append(
            LaserScan(
                header=Header(stamp=Time(sec=100 + k // 10, nanosec=(k % 10) * 100_000_000), frame_id="laser"),
                angle_min=-np.pi / 2,
                angle_max=np.pi / 2,
                angle_increment=np.pi / 180,
                time_increment=0.0,
                scan_time=0.1,
                range_min=0.02,
                range_max=5.6,
                ranges=ranges,
                intensities=np.zeros(0, dtype=np.float32),
            )
        )
    return out


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_ros2_bag_round_trip(tmp_path, storage):
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    typestore = get_typestore(Stores.ROS2_HUMBLE)
    path = tmp_path / "bag"
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    with Writer(path, version=9, storage_plugin=plugin) as writer:
        connection = writer.add_connection("/scan", "sensor_msgs/msg/LaserScan", typestore=typestore)
        for k, message in enumerate(laser_messages(typestore)):
            writer.write(connection, 1_000 + k, typestore.serialize_cdr(message, "sensor_msgs/msg/LaserScan"))
    for source in [path] + (
        [next(path.glob("*.mcap"))] if storage == "mcap" else []
    ):  # folder, and the bare .mcap file
        scans = list(read_laser_scans(source))
        assert len(scans) == 5
        assert scans[3].stamp_s == pytest.approx(100.3)
        assert scans[0].beam_count == 181 and scans[0].angle_increment_rad == pytest.approx(np.pi / 180)
        assert scans[2].ranges_m[90] == pytest.approx(1.98, abs=1e-6)
        assert scans[0].ranges_m[10] == 0.0 and np.isnan(scans[0].ranges_m[11]) and np.isinf(scans[0].ranges_m[0])
        model = scans[0].scanner_model()
        np.testing.assert_allclose(model.beam_angles_rad() + model.mount_yaw_rad, scans[0].angles_rad(), atol=1e-12)


def test_ros1_bag_round_trip_and_topic_errors(tmp_path):
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    typestore = get_typestore(Stores.ROS1_NOETIC)
    path = tmp_path / "scans.bag"
    messages = laser_messages(get_typestore(Stores.ROS2_HUMBLE))
    with Writer(path) as writer:
        connection = writer.add_connection("/front/scan", "sensor_msgs/msg/LaserScan", typestore=typestore)
        other = writer.add_connection("/rear/scan", "sensor_msgs/msg/LaserScan", typestore=typestore)
        for k, m in enumerate(messages):
            m1 = typestore.types["sensor_msgs/msg/LaserScan"](
                header=typestore.types["std_msgs/msg/Header"](
                    seq=k,
                    stamp=typestore.types["builtin_interfaces/msg/Time"](
                        sec=m.header.stamp.sec, nanosec=m.header.stamp.nanosec
                    ),
                    frame_id="laser",
                ),
                angle_min=m.angle_min,
                angle_max=m.angle_max,
                angle_increment=m.angle_increment,
                time_increment=0.0,
                scan_time=0.1,
                range_min=0.02,
                range_max=5.6,
                ranges=m.ranges,
                intensities=m.intensities,
            )
            raw = typestore.serialize_ros1(m1, "sensor_msgs/msg/LaserScan")
            writer.write(connection, 1_000 + k, raw)
            writer.write(other, 1_000 + k, raw)
    scans = list(read_laser_scans(path, "/front/scan"))
    assert len(scans) == 5 and scans[4].stamp_s == pytest.approx(100.4)
    with pytest.raises(BagError, match="several"):
        list(read_laser_scans(path))
    with pytest.raises(BagError, match="no topic '/nope'"):
        list(read_laser_scans(path, "/nope"))
    with pytest.raises(BagError, match="PoseArray"):
        read_pose_arrays(path)


def test_missing_and_unreadable_files(tmp_path):
    with pytest.raises(FileNotFoundError):
        list(read_laser_scans(tmp_path / "nope.bag"))
    junk = tmp_path / "junk.bag"
    junk.write_bytes(b"not a bag")
    with pytest.raises(BagError, match="not a readable"):
        list(read_laser_scans(junk))


@needs_data
def test_leg_labels_recall_and_precision_on_positive_2():
    from viapath.perception.replay import evaluate_labels, track_recording

    result = track_recording(read_laser_scans(POSITIVE, "/training_scan"), keep_points=False)
    labels = [xy for _, xy in read_pose_arrays(POSITIVE, "/leg_cluster_positions")]
    e = evaluate_labels(result.detections, labels)
    assert e["scans"] == 83 and e["labelled_people"] == 83
    # measured: recall 0.952, precision 0.963, leg recall 0.853 (docs/explanation/perception.md)
    assert e["person_recall"] >= 0.9
    assert e["person_precision_in_wedge"] >= 0.9
    assert e["leg_recall"] >= 0.8
    assert e["person_position_error_median_m"] < 0.12


@needs_data
def test_people_walk_at_plausible_speeds_in_the_demo_recording():
    from viapath.perception.replay import track_recording

    result = track_recording(read_laser_scans(DEMO), keep_points=False)
    assert len(result.times_s) == 1265
    summary = result.track_summary()
    walking = [s for s in summary if s["walking"]]
    speeds = result.walking_speeds()
    # data README: ~2 people per scan, median walking speed 0.67 m/s over 1 s; measured here 0.75 m/s
    assert len(walking) >= 20
    assert 0.5 <= np.median(speeds) <= 1.0
    assert np.percentile(speeds, 90) < 1.8
    static = [s for s in summary if not s["walking"]]
    assert all(s["median_speed_mps"] < 0.2 or s["travel_m"] < 1.0 for s in static)


@needs_data
def test_scans_command_end_to_end(tmp_path):
    import typer
    from typer.testing import CliRunner

    from viapath.cli.scans import scans as scans_command

    app = typer.Typer()

    @app.command()
    def noop() -> None:  # a second command so that `scans` stays a sub-command
        pass

    app.command("scans")(scans_command)
    runner = CliRunner()
    out = tmp_path / "tracks.csv"
    plot = tmp_path / "tracks.png"
    result = runner.invoke(
        app,
        [
            "scans",
            str(POSITIVE),
            "--labels",
            "/leg_cluster_positions",
            "--json",
            "--out",
            str(out),
            "--plot",
            str(plot),
        ],
    )
    assert result.exit_code == 0, result.output
    report = json.loads(result.stdout)
    assert report["scans"] == 83 and report["evaluation"]["person_recall"] >= 0.9
    header = out.read_text().splitlines()[0]
    assert header.startswith("scan,time_s,stamp_s,track_id,x_m,y_m,vx_mps,vy_mps")
    assert plot.stat().st_size > 10_000
    bad = runner.invoke(app, ["scans", str(POSITIVE), "--topic", "/nope"])
    assert bad.exit_code == 2 and "no topic '/nope'" in bad.output and "Traceback" not in bad.output
    missing = runner.invoke(app, ["scans", str(tmp_path / "missing.bag")])
    assert missing.exit_code == 2 and "no such file" in missing.output


def _write_mcap(tmp_path, messages):
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    typestore = get_typestore(Stores.ROS2_HUMBLE)
    path = tmp_path / "bag"
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        connection = writer.add_connection("/scan", "sensor_msgs/msg/LaserScan", typestore=typestore)
        for k, message in enumerate(messages(typestore)):
            writer.write(connection, 1_000 + k, typestore.serialize_cdr(message, "sensor_msgs/msg/LaserScan"))
    return next(path.glob("*.mcap"))


@pytest.mark.parametrize("kept", [0.6, 0.9])
def test_a_cut_off_mcap_is_read_up_to_the_cut_with_a_warning(tmp_path, kept):
    from viapath.io.rosbag import BagWarning

    whole = _write_mcap(tmp_path, lambda typestore: laser_messages(typestore, 40))
    data = whole.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: int(len(data) * kept)])
    with pytest.warns(BagWarning, match="read the"):
        scans = list(read_laser_scans(cut))
    reference = list(read_laser_scans(whole))
    assert 1 <= len(scans) < 40
    for got, expected in zip(scans, reference):  # the intact part, exactly as the whole file has it
        assert got.stamp_s == expected.stamp_s
        np.testing.assert_array_equal(got.ranges_m, expected.ranges_m)


def test_a_scan_with_a_nan_angle_increment_is_named_as_such(tmp_path):
    def messages(typestore):
        out = laser_messages(typestore, 3)
        out[1].angle_increment = float("nan")
        return out

    with pytest.raises(BagError, match="angle_increment nan rad"):
        list(read_laser_scans(_write_mcap(tmp_path, messages)))
