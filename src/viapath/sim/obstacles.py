"""Obstacle motion over a whole episode, computed up front (obstacles do not react to the robot).

Each model yields positions and the velocities a perfect tracker would report, at every step time;
rows are NaN while an obstacle is absent from the scene.
"""

from __future__ import annotations

import numpy as np

from viapath.io.eth_ucy import load_tracks, replay_states


def constant_velocity(start, velocity, times, start_time_s: float = 0.0):
    moving = np.clip(times - start_time_s, 0.0, None)
    positions = np.asarray(start, float) + moving[:, None] * np.asarray(velocity, float)
    velocities = np.where((times >= start_time_s)[:, None], np.asarray(velocity, float), 0.0)
    return positions, velocities


def along_waypoints(start, waypoints, speed_mps: float, times, loop: bool = False, start_time_s: float = 0.0):
    """Walk ``start -> waypoints...`` at constant speed; stop at the end, or go round again if ``loop``."""
    points = np.vstack([np.asarray(start, float), np.asarray(waypoints, float)])
    if loop:
        points = np.vstack([points, points[:1]])
    lengths = np.hypot(*np.diff(points, axis=0).T)
    cumulative = np.concatenate([[0.0], np.cumsum(lengths)])
    total = cumulative[-1]
    distance = np.clip(times - start_time_s, 0.0, None) * speed_mps
    moving = times >= start_time_s
    if loop and total > 0:
        distance = np.mod(distance, total)
    else:
        moving &= distance < total
        distance = np.minimum(distance, total)
    positions = np.stack([np.interp(distance, cumulative, points[:, axis]) for axis in (0, 1)], axis=1)
    segment = np.clip(np.searchsorted(cumulative, distance, side="right") - 1, 0, len(lengths) - 1)
    directions = np.diff(points, axis=0) / np.maximum(lengths, 1e-12)[:, None]
    velocities = np.where(moving[:, None], directions[segment] * speed_mps, 0.0)
    return positions, velocities


def timed_waypoints(start, waypoints, times_of_points, times):
    """Pass through ``start, waypoints...`` at ``times_of_points``, linearly in between; before the
    first time it stands at ``start``, after the last at the end. The velocity reported over a piece
    is that piece's (constant) velocity, zero while standing."""
    points = np.vstack([np.asarray(start, float), np.asarray(waypoints, float)])
    knots = np.asarray(times_of_points, float)
    positions = np.stack([np.interp(times, knots, points[:, axis]) for axis in (0, 1)], axis=1)
    piece_velocities = np.diff(points, axis=0) / np.diff(knots)[:, None]
    piece = np.clip(np.searchsorted(knots, times, side="right") - 1, 0, len(piece_velocities) - 1)
    moving = (times >= knots[0]) & (times < knots[-1])
    velocities = np.where(moving[:, None], piece_velocities[piece], 0.0)
    return positions, velocities


def scenario_obstacle_states(scenario, times: np.ndarray):
    """All obstacles of a scenario at the given times: positions (T, N, 2), velocities (T, N, 2), radii (N,)."""
    columns_p, columns_v, radii = [], [], []
    for item in scenario.obstacles:
        replay = getattr(item, "replay", None)
        if replay is not None:
            tracks = load_tracks(replay.file, replay.dt_s)
            p, v = replay_states(tracks, times + replay.start_s, replay.dt_s, replay.offset)
            columns_p.append(p)
            columns_v.append(v)
            radii.extend([replay.radius] * len(tracks))
            continue
        if item.waypoints is not None and item.times_s is not None:
            p, v = timed_waypoints(item.start, item.waypoints, item.times_s, times)
        elif item.waypoints is not None:
            p, v = along_waypoints(item.start, item.waypoints, item.speed, times, item.loop, item.start_time_s)
        else:
            p, v = constant_velocity(item.start, item.velocity or (0.0, 0.0), times, item.start_time_s)
        columns_p.append(p[:, None])
        columns_v.append(v[:, None])
        radii.append(item.radius)
    if not columns_p:
        return np.zeros((len(times), 0, 2)), np.zeros((len(times), 0, 2)), np.zeros(0)
    return np.concatenate(columns_p, axis=1), np.concatenate(columns_v, axis=1), np.asarray(radii, float)
