"""Write an episode's trace as CSV: one row per control step, SI units in the column names."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np


def write_trace_csv(trace, file: str | Path) -> Path:
    file = Path(file)
    lateral = trace.path.lateral_deviation(trace.robot_poses[:, :2])
    n_obstacles = trace.obstacle_positions.shape[1]
    header = [
        "time_s",
        "x_m",
        "y_m",
        "heading_rad",
        "speed_mps",
        "turn_rate_radps",
        "cmd_speed_mps",
        "cmd_turn_rate_radps",
        "lateral_deviation_m",
        "plan_status",
        "plan_speed_mps",
        "target_x_m",
        "target_y_m",
        "via_x_m",
        "via_y_m",
        "plan_time_ms",
    ]
    header += [f"obstacle{j}_{axis}_m" for j in range(n_obstacles) for axis in ("x", "y")]
    with file.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(header)
        for k in range(len(trace.times_s)):
            via = trace.via_points[k]
            via_xy = [f"{via[0, 0]:.4f}", f"{via[0, 1]:.4f}"] if len(via) else ["", ""]
            plan_ms = trace.plan_times_ms[k]
            row = [
                f"{trace.times_s[k]:.3f}",
                *(f"{v:.4f}" for v in trace.robot_poses[k]),
                f"{trace.robot_speeds_mps[k]:.4f}",
                f"{trace.robot_turn_rates_radps[k]:.4f}",
                f"{trace.commands[k, 0]:.4f}",
                f"{trace.commands[k, 1]:.4f}",
                f"{lateral[k]:.4f}",
                trace.plan_status[k],
                f"{trace.plan_speeds_mps[k]:.4f}",
                f"{trace.plan_targets[k, 0]:.4f}",
                f"{trace.plan_targets[k, 1]:.4f}",
                *via_xy,
                "" if not np.isfinite(plan_ms) else f"{plan_ms:.4f}",
            ]
            obstacles = trace.obstacle_positions[k].ravel()
            row += ["" if not np.isfinite(v) else f"{v:.4f}" for v in obstacles]
            writer.writerow(row)
    return file
