"""How sharply do real walkers change velocity? Accelerations on the ETH/UCY recordings, away from annotation corners.

Usage: python benchmarks/walker_accel.py [--data DIR] [--windows 0.8,1.0,1.2] [--grid 0.1] [--json]

The recordings are positions every row step (0.4 s; 2/3 s in biwi_eth.txt, see the data README),
replayed linearly in between (viapath.io.eth_ucy): a replayed person's velocity jumps at every row (an
"annotation corner") and is constant in between, so the acceleration of the replay itself is 0 or
infinite. What a walker does is measured over a window W instead: on each track, sampled every
``--grid`` seconds of its linear replay, the central second difference

    a(t) = |p(t + W) − 2 p(t) + p(t − W)| / W²

which is the walker's acceleration averaged with a triangle of half-width W around t (a corner
counts, spread over the window, never as a spike). Also printed: the velocity change at each corner
over one row step (W = one row, the replay's own "acceleration"), for comparison.

Percentiles 50/90/95/99 of a(t) over time (every track's samples pooled), per scene and over all
scenes, for all people and for walking ones (mean speed over [t − W, t + W] ≥ 0.5 m/s). Compare with
the shield's bound ``person_accel_mps2`` (viapath.safety.options). Reads the data in place.
"""

from __future__ import annotations

import argparse
import json
import os
from pathlib import Path

import numpy as np

from viapath.io.eth_ucy import load_tracks
from viapath.safety.options import option_defaults

FILES = [  # (file, seconds per row step): the data README §1
    ("biwi_eth.txt", 2.0 / 3.0),
    ("biwi_hotel.txt", 0.4),
    ("students001.txt", 0.4),
    ("students003.txt", 0.4),
    ("crowds_zara01.txt", 0.4),
    ("crowds_zara02.txt", 0.4),
    ("crowds_zara03.txt", 0.4),
    ("uni_examples.txt", 0.4),
]
PERCENTILES = (50, 90, 95, 99)
WALKING_MPS = 0.5


def windowed(tracks, window_s: float, grid_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Accelerations a(t) (m/s²) and mean speeds over [t − W, t + W] of every track's linear replay."""
    accels, speeds = [], []
    for track in tracks:
        start, end = track.times_s[0] + window_s, track.times_s[-1] - window_s
        if end < start:
            continue
        t = np.arange(start, end + 1e-9, grid_s)

        def at(times, track=track):
            return np.stack([np.interp(times, track.times_s, track.positions[:, a]) for a in (0, 1)], axis=1)

        before, now, after = at(t - window_s), at(t), at(t + window_s)
        accels.append(np.hypot(*(after - 2 * now + before).T) / window_s**2)
        speeds.append(np.hypot(*(after - before).T) / (2 * window_s))
    if not accels:
        return np.zeros(0), np.zeros(0)
    return np.concatenate(accels), np.concatenate(speeds)


def corners(tracks, dt_s: float) -> np.ndarray:
    """The velocity change at each annotation corner over one row step (m/s²)."""
    out = []
    for track in tracks:
        velocity = np.diff(track.positions, axis=0) / dt_s
        if len(velocity) > 1:
            out.append(np.hypot(*np.diff(velocity, axis=0).T) / dt_s)
    return np.concatenate(out) if out else np.zeros(0)


def _percentiles(values: np.ndarray) -> dict:
    if not len(values):
        return {"samples": 0}
    return {"samples": len(values), **{f"p{p}": float(np.percentile(values, p)) for p in PERCENTILES}}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    default_data = Path(os.environ.get("VIAPATH_DATA", Path(__file__).resolve().parents[1] / ".." / "shared" / "data"))
    parser.add_argument("--data", type=Path, default=default_data, help="folder holding eth_ucy_trajectron/")
    parser.add_argument("--windows", default="0.8,1.0,1.2", help="window half-widths W in seconds")
    parser.add_argument("--grid", type=float, default=0.1, help="sampling step along each track, s")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    folder = args.data / "eth_ucy_trajectron"
    if not folder.is_dir():
        raise SystemExit(f"{folder}: not found; give --data (the folder holding eth_ucy_trajectron/) or VIAPATH_DATA")
    windows = [float(w) for w in args.windows.split(",") if w.strip()]
    result: dict = {"windows_s": windows, "grid_s": args.grid, "scenes": {}, "all": {}}
    pooled: dict = {w: ([], []) for w in windows}
    pooled_corners = []
    for name, dt in FILES:
        tracks = load_tracks(folder / name, dt)
        scene: dict = {"tracks": len(tracks), "row_step_s": dt, "corner": _percentiles(corners(tracks, dt))}
        pooled_corners.append(corners(tracks, dt))
        for w in windows:
            accel, speed = windowed(tracks, w, args.grid)
            pooled[w][0].append(accel)
            pooled[w][1].append(speed)
            scene[f"W={w:g}s"] = {
                "all": _percentiles(accel),
                "walking": _percentiles(accel[speed >= WALKING_MPS]),
            }
        result["scenes"][name] = scene
    result["all"]["corner"] = _percentiles(np.concatenate(pooled_corners))
    for w in windows:
        accel, speed = np.concatenate(pooled[w][0]), np.concatenate(pooled[w][1])
        result["all"][f"W={w:g}s"] = {"all": _percentiles(accel), "walking": _percentiles(accel[speed >= WALKING_MPS])}
    bound = float(option_defaults()["person_accel_mps2"])
    result["shield_person_accel_mps2"] = bound
    if args.json:
        print(json.dumps(result, indent=2))
        return
    header = "| scene | window | people | " + " | ".join(f"p{p}" for p in PERCENTILES) + " |"
    print(f"Walker accelerations [m/s²] (|p(t+W) − 2p(t) + p(t−W)| / W², every {args.grid:g} s of each track)")
    print()
    print(header)
    print("|---|---|---|" + "---|" * len(PERCENTILES))
    rows = [(name, result["scenes"][name]) for name, _ in FILES] + [("all scenes", result["all"])]
    for name, scene in rows:
        for key in [f"W={w:g}s" for w in windows]:
            for who in ("all", "walking"):
                stats = scene[key][who]
                cells = " | ".join(f"{stats[f'p{p}']:.2f}" if stats["samples"] else "–" for p in PERCENTILES)
                print(f"| {name} | {key} | {who} | {cells} |")
        stats = scene["corner"]
        cells = " | ".join(f"{stats[f'p{p}']:.2f}" for p in PERCENTILES)
        print(f"| {name} | one row (corner) | all | {cells} |")
    print()
    print(f"shield bound person_accel_mps2 (default): {bound:g} m/s²")


if __name__ == "__main__":
    main()
