"""Property test of the shield with static geometry (docs/design.md §10) against an independent brute force.

2 000 random single cycles (10 000 with VIAPATH_FULL_TESTS=1, tests/_sizes.py) (seeded): robot state, motion limits, control period, margin, 1-8 static
points and segments (a wall, a box edge, a scan return) around the robot, and 0-3 people. The static
layer goes through the guard's sampling into discs (:func:`viapath.guard.with_static_rows`), as every
planner's does, and then through the shield. The brute force knows nothing of discs: it steps the drive
finely (tests/safety/_brute.py's stepping, written again here for segments) and measures the exact
distance from the robot centre to each segment. Checks, for each cycle:

* the output is finite and inside the limits;
* soundness: when the shield says its output is admissible, then while the robot moves it never comes
  nearer to a static segment than ``radius + margin`` unless it was nearer already, and then not nearer
  than it was (less the discs' sampling pad, which the shield may spend there), and the people's brute
  force (tests/safety/_brute.py) agrees too;
* completeness (on the first 2 000 cycles: the brute force over the window is the slow part): when some
  command of an 11 x 11 grid over the dynamic window keeps ``ROBUST_M`` more than ``radius + margin``
  from every segment and is admissible for the people with ``ROBUST_M`` to spare, the shield's output
  is admissible by both brute forces.
"""

from __future__ import annotations

import numpy as np

from tests._sizes import cases
from tests.safety._brute import brute_admissible, window_grid
from viapath.guard import DEFAULT_CONFIG, with_static_rows
from viapath.observation import Command, MotionLimits, Observation, Obstacles, RobotState
from viapath.safety import Shield, ShieldConfig
from viapath.static import StaticLayer

ROBUST_M = 0.03  # the discs' pad (<= 2 cm for the radii drawn) and the brute force's time sampling
GRID = 11
COMPLETENESS_CYCLES = 2_000
MAX_STATIC = 8
MAX_PEOPLE = 3
FINE = 8


def random_cases(rng: np.random.Generator, count: int) -> dict:
    vmax = rng.uniform(0.2, 1.2, count)
    wmax = rng.uniform(0.5, 3.0, count)
    case = {
        "x": rng.uniform(-5, 5, count),
        "y": rng.uniform(-5, 5, count),
        "heading": rng.uniform(-np.pi, np.pi, count),
        "speed": vmax * rng.choice([0.0, 1.0, 1.0, 1.0], count) * rng.uniform(0, 1, count),
        "turn": wmax * rng.uniform(-1, 1, count),
        "radius": rng.uniform(0.15, 0.4, count),
        "vmax": vmax,
        "amax": rng.uniform(0.4, 2.0, count),
        "wmax": wmax,
        "alphamax": rng.uniform(1.0, 10.0, count),
        "dt": rng.choice([0.05, 0.1, 0.2], count),
        "margin": rng.uniform(0.0, 0.2, count),
        "accel_p": rng.uniform(0.0, 2.0, count),
        "k_sigma": rng.uniform(0.0, 3.0, count),
    }
    # Static: segments of 0-3 m (a quarter of them points) with their middle 0.1-3 m from the robot.
    n_static = rng.integers(1, MAX_STATIC + 1, count)
    distance = rng.uniform(0.1, 3.0, (count, MAX_STATIC))
    bearing = rng.uniform(-np.pi, np.pi, (count, MAX_STATIC))
    middle = np.stack(
        [case["x"][:, None] + distance * np.cos(bearing), case["y"][:, None] + distance * np.sin(bearing)], -1
    )
    length = rng.uniform(0.0, 3.0, (count, MAX_STATIC)) * (rng.uniform(size=(count, MAX_STATIC)) > 0.25)
    angle = rng.uniform(-np.pi, np.pi, (count, MAX_STATIC))
    half = 0.5 * length[..., None] * np.stack([np.cos(angle), np.sin(angle)], -1)
    segments = np.stack([middle - half, middle + half], axis=2)  # (B, S, 2, 2)
    absent = np.arange(MAX_STATIC)[None, :] >= n_static[:, None]
    segments[absent] = 1e4
    case.update(segments=segments, n_static=n_static)
    # People: 0-3, 0.3-4 m away, as in test_shield_property.
    n_people = rng.integers(0, MAX_PEOPLE + 1, count)
    distance = rng.uniform(0.3, 4.0, (count, MAX_PEOPLE))
    bearing = rng.uniform(-np.pi, np.pi, (count, MAX_PEOPLE))
    P = np.stack([case["x"][:, None] + distance * np.cos(bearing), case["y"][:, None] + distance * np.sin(bearing)], -1)
    speed = rng.uniform(0.0, 1.5, (count, MAX_PEOPLE))
    heading = rng.uniform(-np.pi, np.pi, (count, MAX_PEOPLE))
    V = np.stack([speed * np.cos(heading), speed * np.sin(heading)], -1)
    absent = np.arange(MAX_PEOPLE)[None, :] >= n_people[:, None]
    P[absent], V[absent] = 1e4, 0.0
    case.update(
        P=P,
        V=V,
        r=rng.uniform(0.1, 0.35, (count, MAX_PEOPLE)),
        sigma_v=np.zeros((count, MAX_PEOPLE)),
        sigma_p=np.zeros((count, MAX_PEOPLE)),
        n_people=n_people,
    )
    return case


def point_segment_distance(px, py, segments):
    """Distance from points (..., 1) to segments (..., S, 2, 2) broadcast, written plainly."""
    ax, ay = segments[..., 0, 0], segments[..., 0, 1]
    bx, by = segments[..., 1, 0], segments[..., 1, 1]
    dx, dy = bx - ax, by - ay
    length2 = dx * dx + dy * dy
    t = np.where(length2 > 0, ((px - ax) * dx + (py - ay) * dy) / np.where(length2 > 0, length2, 1.0), 0.0)
    t = np.clip(t, 0.0, 1.0)
    return np.hypot(px - (ax + t * dx), py - (ay + t * dy))


def brute_static(case: dict, commands: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For each (case, command): the smallest distance to each segment while moving, less its distance now
    (B, K, S) as (closest while moving, distance now). The drive is stepped as tests/safety/_brute.py does."""
    c = {key: np.asarray(value, dtype=float) for key, value in case.items()}
    b_count, k_count = commands.shape[:2]
    col = lambda name: c[name][:, None]
    seg = c["segments"][:, None]  # (B, 1, S, 2, 2)
    v_cmd = np.clip(commands[..., 0], 0.0, col("vmax"))
    w_cmd = np.clip(commands[..., 1], -col("wmax"), col("wmax"))
    dv, dw = col("amax") * col("dt"), col("alphamax") * col("dt")
    speed = col("speed") + np.clip(v_cmd - col("speed"), -dv, dv)
    turn = col("turn") + np.clip(w_cmd - col("turn"), -dw, dw)
    x = np.broadcast_to(col("x"), (b_count, k_count)).copy()
    y = np.broadcast_to(col("y"), (b_count, k_count)).copy()
    heading = np.broadcast_to(col("heading"), (b_count, k_count)).copy()
    now = point_segment_distance(x[..., None], y[..., None], seg)  # (B, K, S)
    closest = np.full_like(now, np.inf)
    previous = np.broadcast_to(col("speed"), (b_count, k_count)).copy()
    moving = (speed != 0.0) | (previous != 0.0)
    h = col("dt") / FINE
    steps = 0
    while np.any(moving):
        for _ in range(FINE):
            mid = heading + 0.5 * turn * h
            x = x + np.where(moving, speed * h * np.cos(mid), 0.0)
            y = y + np.where(moving, speed * h * np.sin(mid), 0.0)
            heading = heading + turn * h
            d = point_segment_distance(x[..., None], y[..., None], seg)
            closest = np.where(moving[..., None], np.minimum(closest, d), closest)
        previous = speed
        speed = speed + np.clip(-speed, -dv, dv)
        turn = turn + np.clip(-turn, -dw, dw)
        moving = moving & ((speed != 0.0) | (previous != 0.0))
        steps += 1
        assert steps < 10_000
    return closest, now


def run_shield(case: dict, commands: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    outputs, claimed = np.zeros((len(commands), 2)), np.zeros(len(commands), dtype=bool)
    largest_pad = np.zeros(len(commands))
    for b in range(len(commands)):
        limits = MotionLimits(case["vmax"][b], case["amax"][b], case["wmax"][b], case["alphamax"][b])
        config = ShieldConfig(
            margin_m=case["margin"][b],
            person_accel_mps2=case["accel_p"][b],
            sigma_multiplier=case["k_sigma"][b],
        )
        n = int(case["n_people"][b])
        people = Obstacles(case["P"][b, :n], case["V"][b, :n], case["r"][b, :n])
        robot = RobotState(
            np.array([case["x"][b], case["y"][b]]),
            case["heading"][b],
            case["speed"][b],
            case["turn"][b],
            case["radius"][b],
        )
        static = StaticLayer(case["segments"][b, : int(case["n_static"][b])])
        observation = with_static_rows(Observation(0.0, robot, people, static))
        largest_pad[b] = observation.obstacles.statics().radii_m.max()
        result = Shield(limits, float(case["dt"][b]), config).filter(observation, Command(*commands[b]))
        outputs[b] = result.command.speed_mps, result.command.turn_rate_radps
        claimed[b] = result.admissible
    return outputs, claimed, largest_pad


def test_static_discs_cover_segments_within_the_pad():
    """The sampling the guard applies (spacing and pad) is what the soundness bound below relies on."""
    assert DEFAULT_CONFIG.static_spacing_m <= 0.15
    robot = RobotState(np.zeros(2), 0.0, 0.0, 0.0, 0.15)
    observation = with_static_rows(
        Observation(0.0, robot, Obstacles.empty(), StaticLayer(np.array([[[1.0, 0], [4.0, 0]]])))
    )
    assert observation.obstacles.statics().radii_m.max() <= 0.02


def test_shield_with_static_geometry_against_brute_force(count: int = cases(2_000, 10_000)):
    rng = np.random.default_rng(5)
    case = random_cases(rng, count)
    commands = np.stack([rng.uniform(-0.2, 1.3, count) * case["vmax"], rng.uniform(-1.3, 1.3, count) * case["wmax"]], 1)
    totals = {"exists": 0, "claimed": 0, "inside_now": 0}
    for start in range(0, count, 500):
        index = np.arange(start, min(count, start + 500))
        sub = {key: value[index] for key, value in case.items()}
        outputs, claimed, pad = run_shield(sub, commands[index])
        assert np.all(np.isfinite(outputs))
        assert np.all(outputs[:, 0] >= 0.0) and np.all(outputs[:, 0] <= sub["vmax"] + 1e-12)
        assert np.all(np.abs(outputs[:, 1]) <= sub["wmax"] + 1e-12)
        reach = (sub["radius"] + sub["margin"])[:, None]  # (B, 1)
        closest, now = brute_static(sub, outputs[:, None, :])
        closest, now = closest[:, 0], now[:, 0]  # (B, S)
        # Clear of every disc now: clear of every segment's capsule all along. Nearer already: not nearer than
        # now, less the pad the shield may spend. (1e-4 m: the brute force's midpoint steps.)
        bound = np.where(now >= reach + pad[:, None], reach, np.minimum(reach, now) - pad[:, None]) - 1e-4
        static_ok = np.all(closest >= bound, axis=1)
        people_ok = brute_admissible(sub, outputs[:, None, :])[:, 0]
        bad = np.flatnonzero(claimed & ~(static_ok & people_ok))
        assert len(bad) == 0, f"shield claimed admissible, brute force disagrees: cases {index[bad[:5]]}"
        totals["claimed"] += int(claimed.sum())
        totals["inside_now"] += int((~np.all(now >= reach, axis=1)).sum())
        if start >= COMPLETENESS_CYCLES:
            continue
        grid = window_grid(sub, GRID)
        grid_closest, _ = brute_static(sub, grid)
        robust = np.all(grid_closest >= reach[:, None] + ROBUST_M, axis=2) & brute_admissible(
            sub, grid, extra_m=ROBUST_M
        )
        exists = robust.any(axis=1)
        clear_now = np.all(now >= reach + ROBUST_M, axis=1)
        bad = np.flatnonzero(exists & ~(static_ok & people_ok))
        assert len(bad) == 0, f"an admissible command exists but the shield's output is not: cases {index[bad[:5]]}"
        bad = np.flatnonzero(exists & clear_now & ~claimed)
        assert len(bad) == 0, f"an admissible command exists but the shield says none is: cases {index[bad[:5]]}"
        totals["exists"] += int(exists.sum())
    # The draw exercises every side: cycles with and without a way out, and robots already too near.
    assert COMPLETENESS_CYCLES // 4 < totals["exists"] < COMPLETENESS_CYCLES
    assert totals["inside_now"] > count // 50
