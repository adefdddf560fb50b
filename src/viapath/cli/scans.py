"""``viapath scans BAG``: detection and tracking over a recorded laser scan sequence.

Everything heavy is imported inside the command so that ``viapath --help`` stays fast and works
without the optional ``rosbags``.
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import typer
from rich.table import Table

from viapath.cli.common import check_output, console, fail


def _finite(value):
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def scans(
    bag: Path = typer.Argument(
        ..., help="ROS 1 .bag, ROS 2 bag folder, .db3 or .mcap file with sensor_msgs/LaserScan."
    ),
    topic: str | None = typer.Option(None, "--topic", help="LaserScan topic (default: the only one)."),
    plot: Path | None = typer.Option(None, "--plot", help="Write a figure (PNG/PDF/SVG): tracks and walking speeds."),
    out: Path | None = typer.Option(None, "--out", help="Write every confirmed track state per scan as CSV."),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object (summary, tracks, evaluation)."),
    labels: str | None = typer.Option(
        None, "--labels", help="PoseArray topic of labelled legs: report recall/precision."
    ),
    max_rows: int = typer.Option(25, "--max-rows", min=1, help="Tracks shown in the table (longest first)."),
) -> None:
    """Detect and track people in a laser recording; report the tracks (id, time, position, velocity)."""
    from viapath.io.rosbag import BagError, RosbagsMissingError, read_laser_scans, read_pose_arrays
    from viapath.perception.replay import evaluate_labels, track_recording

    check_output(plot, (".png", ".pdf", ".svg"), "--plot")
    check_output(out, (".csv",), "--out")
    if not bag.exists():
        fail(f"{bag}: no such file or directory")
    try:
        result = track_recording(read_laser_scans(bag, topic), keep_points=plot is not None)
        evaluation = None
        if labels is not None:
            label_messages = [xy for _, xy in read_pose_arrays(bag, labels)]
            evaluation = evaluate_labels(result.detections, label_messages)
    except RosbagsMissingError as error:
        fail(str(error))
    except (BagError, FileNotFoundError, ValueError) as error:
        fail(str(error))
    if len(result.times_s) == 0:
        fail(f"{bag}: the topic holds no scans")

    summary = result.track_summary()
    walking = [s for s in summary if s["walking"]]
    speeds = result.walking_speeds()
    report = {
        "bag": str(bag),
        "scans": len(result.times_s),
        "duration_s": float(result.times_s[-1]),
        "confirmed_tracks": len(summary),
        "walking_tracks": len(walking),
        "walking_speed_median_mps": float(np.median(speeds)) if len(speeds) else None,
        "walking_speed_p25_mps": float(np.percentile(speeds, 25)) if len(speeds) else None,
        "walking_speed_p75_mps": float(np.percentile(speeds, 75)) if len(speeds) else None,
        "detections_per_scan_median": float(np.median([len(d) for d in result.detections])),
        "tracks": summary,
    }
    if evaluation is not None:
        report["evaluation"] = evaluation

    if out is not None:
        _write_csv(out, result)
    if plot is not None:
        from viapath.perception.plotting import plot_recording

        plot_recording(result, plot, title=f"{bag.name}: {len(walking)} walking tracks")

    if as_json:
        print(json.dumps({k: _finite(v) for k, v in report.items()}, default=_json_default))
        return
    _print_report(report, summary, max_rows, out, plot)


def _json_default(value):
    if isinstance(value, (np.floating, np.integer)):
        return value.item()
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


def _write_csv(path: Path, result) -> None:
    with path.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(
            [
                "scan",
                "time_s",
                "stamp_s",
                "track_id",
                "x_m",
                "y_m",
                "vx_mps",
                "vy_mps",
                "speed_mps",
                "radius_m",
                "position_sigma_m",
                "velocity_sigma_mps",
            ]
        )
        for row, vel_sigma in zip(result.track_rows, result.velocity_sigma_mps, strict=True):
            scan, t, tid, x, y, vx, vy, radius, pos_sigma = row
            writer.writerow(
                [
                    int(scan),
                    f"{t:.4f}",
                    f"{t + result.start_stamp_s:.4f}",
                    int(tid),
                    f"{x:.4f}",
                    f"{y:.4f}",
                    f"{vx:.4f}",
                    f"{vy:.4f}",
                    f"{math.hypot(vx, vy):.4f}",
                    f"{radius:.4f}",
                    f"{pos_sigma:.4f}",
                    f"{vel_sigma:.4f}",
                ]
            )


def _print_report(report: dict, summary: list[dict], max_rows: int, out, plot) -> None:
    table = Table(
        title=f"{report['bag']}: {report['scans']} scans over {report['duration_s']:.1f} s, "
        f"{report['confirmed_tracks']} confirmed tracks ({report['walking_tracks']} walking)"
    )
    for column in (
        "id",
        "first [s]",
        "duration [s]",
        "start (x, y) [m]",
        "end (x, y) [m]",
        "moved [m]",
        "median speed [m/s]",
        "walking",
    ):
        table.add_column(column, justify="right")
    for s in sorted(summary, key=lambda s: -s["duration_s"])[:max_rows]:
        table.add_row(
            str(s["track_id"]),
            f"{s['first_s']:.1f}",
            f"{s['duration_s']:.1f}",
            f"({s['start_x_m']:.2f}, {s['start_y_m']:.2f})",
            f"({s['end_x_m']:.2f}, {s['end_y_m']:.2f})",
            f"{s['travel_m']:.2f}",
            f"{s['median_speed_mps']:.2f}",
            "yes" if s["walking"] else "",
        )
    console.print(table)
    if len(summary) > max_rows:
        console.print(f"({len(summary) - max_rows} shorter tracks not shown; --max-rows, --out or --json for all)")
    if report["walking_speed_median_mps"] is not None:
        console.print(
            f"walking speed: median {report['walking_speed_median_mps']:.2f} m/s "
            f"(p25 {report['walking_speed_p25_mps']:.2f}, p75 {report['walking_speed_p75_mps']:.2f})"
        )
    if "evaluation" in report:
        e = report["evaluation"]
        console.print(
            f"labels: person recall {e['person_recall']:.3f} ({e['labelled_people']} labelled), precision in the "
            f"±15°/5 m wedge {e['person_precision_in_wedge']:.3f} ({e['false_positives_in_wedge']} false), "
            f"leg recall {e['leg_recall']:.3f}, median person error {e['person_position_error_median_m']:.3f} m"
        )
    if out is not None:
        console.print(f"tracks written to {out}")
    if plot is not None:
        console.print(f"figure written to {plot}")
