"""ETH/UCY pedestrian trajectories in the common 4-column text format: ``frame ped_id x y`` (metres).

Rows step 10 video frames; one row step lasts ``dt_s`` (0.4 s for every file of the usual
Trajectron++/S-GAN split except ``biwi_eth.txt``, where it is 2/3 s: see the data README).

For replay in the simulator, positions are interpolated linearly between samples, and the velocity
given to the planner is estimated from *past* positions only (a backward difference over one row
step), as a tracker would: a replayed person is never forecast from the future. A person's first
sample has no past: they walked into the recorded area, they did not appear standing, so before it
they are taken to have walked as over their first interval, and the velocity at the first sample is
that interval's. A person is seen, with position and velocity, from the first sample on (the cycle a
robot could first react to them; :func:`viapath.sim.metrics.first_seen_steps`).
"""

from __future__ import annotations

import io
from dataclasses import dataclass
from pathlib import Path

import numpy as np

FRAMES_PER_ROW = 10


@dataclass(frozen=True)
class PedestrianTrack:
    ped_id: int
    times_s: np.ndarray  # (K,) scene time
    positions: np.ndarray  # (K, 2) m


def load_tracks(file: str | Path, dt_s: float) -> list[PedestrianTrack]:
    """Read a 4-column trajectory file; scene time of a row is ``frame / 10 * dt_s``."""
    from viapath.io.safe_read import InputError, read_text_file

    path = Path(file)
    if not path.exists():
        where = path if path.is_absolute() else f"{path} (resolved: {path.resolve()})"
        raise FileNotFoundError(f"{where}: cannot read trajectory file: No such file or directory")
    try:
        text = read_text_file(path, what="trajectory file (4 columns 'frame ped_id x y')")
    except InputError as error:
        raise ValueError(str(error)) from None
    try:
        table = np.loadtxt(io.StringIO(text), ndmin=2)
    except ValueError as error:
        raise ValueError(f"{path}: expected 4 numeric columns 'frame ped_id x y': {error}") from None
    if table.shape[1] != 4:
        raise ValueError(f"{path}: expected 4 columns 'frame ped_id x y', found {table.shape[1]}")
    if not np.isfinite(table).all():
        raise ValueError(f"{path}: contains NaN or infinite values")
    # One sort by (id, frame) and a split: linear after the sort in the number of people (a filter per
    # person was quadratic: 40 000 people took 19 s).
    table = table[np.lexsort((table[:, 0], table[:, 1]))]
    ids, first = np.unique(table[:, 1], return_index=True)
    bounds = np.append(first, len(table)).tolist()
    times = table[:, 0] / FRAMES_PER_ROW * dt_s
    positions = np.ascontiguousarray(table[:, 2:4])
    return [
        PedestrianTrack(int(ped_id), times[a:b].copy(), positions[a:b].copy())
        for ped_id, a, b in zip(ids.tolist(), bounds[:-1], bounds[1:])
    ]


def replay_states(tracks: list[PedestrianTrack], scene_times_s: np.ndarray, dt_s: float, offset=(0.0, 0.0)):
    """Positions and past-only velocity estimates of every track at the given scene times.

    Returns ``(positions (T, N, 2), velocities (T, N, 2))`` with NaN rows where a person is not in
    the scene (before their first or after their last sample).
    """
    scene_times_s = np.asarray(scene_times_s, dtype=float)
    n_times, n_tracks = len(scene_times_s), len(tracks)
    positions = np.full((n_times, n_tracks, 2), np.nan)
    velocities = np.full((n_times, n_tracks, 2), np.nan)
    offset = np.asarray(offset, dtype=float)
    for j, track in enumerate(tracks):
        present = (scene_times_s >= track.times_s[0]) & (scene_times_s <= track.times_s[-1])
        if not present.any():
            continue
        t = scene_times_s[present]
        now = _interpolate(track, t)
        before_t = np.maximum(t - dt_s, track.times_s[0])
        before = _interpolate(track, before_t)
        span = t - before_t
        first = _first_interval_velocity(track)
        with np.errstate(invalid="ignore", divide="ignore"):
            velocity = np.where(span[:, None] > 1e-9, (now - before) / span[:, None], first)
        positions[present, j] = now + offset
        velocities[present, j] = velocity
    return positions, velocities


def _first_interval_velocity(track: PedestrianTrack) -> np.ndarray:
    """The velocity between a track's first two samples (zero for a single sample)."""
    if len(track.times_s) < 2 or track.times_s[1] <= track.times_s[0]:
        return np.zeros(2)
    return (track.positions[1] - track.positions[0]) / (track.times_s[1] - track.times_s[0])


def _interpolate(track: PedestrianTrack, times: np.ndarray) -> np.ndarray:
    return np.stack([np.interp(times, track.times_s, track.positions[:, axis]) for axis in (0, 1)], axis=1)
