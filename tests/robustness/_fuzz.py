"""Hypothesis strategies for the guarded entry (issue 12): observations with NaN / inf / negative /
huge fields and wrong shapes mixed into valid ones. Shared by the CI tests and benchmarks/fuzz_entry.py."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import strategies as st

from viapath.observation import Observation, ObservationError, Obstacles, RobotState

BAD = [math.nan, math.inf, -math.inf, 1e300, -1e300]


def _mixed(valid, bad_values=BAD, valid_weight: int = 4):
    return st.one_of(*([valid] * valid_weight), st.sampled_from(bad_values))


def _fill(rng: np.random.Generator, shape, low: float, high: float, bad_values, bad_rate: float) -> np.ndarray:
    """Uniform valid values with a fraction ``bad_rate`` replaced by picks from ``bad_values``."""
    values = rng.uniform(low, high, shape)
    bad = rng.random(shape) < bad_rate
    values[bad] = rng.choice(np.asarray(bad_values, dtype=float), size=int(bad.sum()))
    return values


SHAPE_FAULTS = ["none"] * 20 + ["transposed", "short-velocities", "radii-length", "flat", "bypass"]


@st.composite
def observation_batches(draw, size: int = 5, max_obstacles: int = 6):
    """``size`` observations (a stream of cycles), each an Observation or the ObservationError raised
    while building one with wrong shapes (the documented error: the caller checks that nothing else
    is raised).

    Hypothesis draws the structure (how often robot fields and obstacle fields are bad, the shape
    faults) and a seed; the numbers come from a numpy generator seeded by it, several observations
    per example: as reproducible as hypothesis' own choices and ~10x cheaper per observation."""
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    robot_bad = draw(st.sampled_from([0.0, 0.0, 0.0, 0.0, 0.02, 0.2]))
    field_bad = draw(st.sampled_from([0.0, 0.1, 0.3, 0.6]))
    faults = [draw(st.sampled_from(SHAPE_FAULTS)) for _ in range(size)]
    return [_observation(rng, robot_bad, field_bad, fault, max_obstacles) for fault in faults]


def _observation(rng, robot_bad: float, field_bad: float, shape_fault: str, max_obstacles: int):
    n = int(rng.integers(0, max_obstacles + 1))
    x, y = _fill(rng, 2, -6.0, 6.0, BAD, robot_bad)
    heading = _fill(rng, 1, -7.0, 7.0, BAD, robot_bad)[0]
    speed = _fill(rng, 1, -0.3, 0.8, BAD, robot_bad)[0]
    turn = _fill(rng, 1, -2.5, 2.5, BAD, robot_bad)[0]
    radius_m = 0.25 if rng.random() >= robot_bad else float(rng.choice([np.nan, -0.1, 0.0, np.inf]))
    robot = RobotState(np.array([x, y]), heading, speed, turn, radius_m)
    base = np.where(np.isfinite([x, y]) & (np.abs([x, y]) < 1e6), [x, y], 0.0)
    positions = base + _fill(rng, (n, 2), -3.0, 3.0, BAD, field_bad / 20)
    velocities = _fill(rng, (n, 2), -1.5, 1.5, BAD + [50.0], field_bad)
    radii = _fill(rng, n, 0.0, 1.0, BAD + [-0.25, -1e-9, 0.0], field_bad)
    position_sigma = _fill(rng, n, 0.0, 0.5, BAD + [-0.1, 5.0], field_bad)
    velocity_sigma = _fill(rng, n, 0.0, 0.5, BAD + [-0.1, 5.0], field_bad)
    time_s = float(rng.uniform(0.0, 100.0)) if rng.random() > robot_bad else float(rng.choice([np.nan, np.inf]))
    try:
        if shape_fault == "transposed" and n not in (0, 2):
            obstacles = Obstacles(positions.T, velocities.T, radii)
        elif shape_fault == "short-velocities" and n > 0:
            obstacles = Obstacles(positions, velocities[:-1], radii)
        elif shape_fault == "radii-length" and n > 1:
            obstacles = Obstacles(positions, velocities, radii[:-1])
        elif shape_fault == "flat" and n > 1:
            obstacles = Obstacles(positions.ravel()[:-1], velocities, radii)
        else:
            obstacles = Obstacles(positions, velocities, radii, position_sigma, velocity_sigma)
            if shape_fault == "bypass" and n > 0:
                # Built right, then broken behind the constructor's back: the guard must still refuse it.
                object.__setattr__(obstacles, "velocities", np.zeros((n + 1, 2)))
    except ObservationError as error:
        return error
    return Observation(time_s, robot, obstacles)


# -- the laser path ---------------------------------------------------------------------------------

range_value = _mixed(st.floats(0.02, 5.6), [0.0, math.nan, math.inf, -math.inf, -1.0, 1e300], valid_weight=3)


@st.composite
def scan_sets(draw, beam_counts: tuple[int, ...]):
    """What the drivers hand over for each scanner: a scan (right length, or not), None (no message
    this cycle), or a list with a scanner missing."""
    scans = []
    for count in beam_counts:
        kind = draw(st.sampled_from(["good"] * 6 + ["all-invalid", "short", "long", "none", "2d"]))
        if kind == "none":
            scans.append(None)
            continue
        length = {"short": count - draw(st.integers(1, count)), "long": count + draw(st.integers(1, 50))}.get(
            kind, count
        )
        fill = draw(st.sampled_from(["walls", "mixed", "person"]))
        if kind == "all-invalid":
            values = np.full(length, draw(st.sampled_from([0.0, math.nan, math.inf])))
        elif fill == "walls":
            values = np.full(length, draw(st.floats(0.3, 4.0)))
        elif fill == "person":
            values = np.full(length, math.inf)
            start = draw(st.integers(0, max(0, length - 20)))
            values[start : start + 15] = draw(st.floats(0.4, 3.0))
        else:
            values = np.array([draw(range_value) for _ in range(min(length, 40))])
            values = np.resize(values, length) if length else values[:0]
        if kind == "2d":
            values = np.stack([values, values])
        scans.append(values)
    if draw(st.integers(0, 9)) == 0 and scans:
        scans = scans[:-1]  # a scanner missing from the list
    return scans
