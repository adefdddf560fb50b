"""Scenario suites generated from a seed, written as scenario YAML so they can be inspected and rerun.

Every generated scenario is a plain scenario (docs/design.md §4): a straight designated path from the origin
along +x (length 6-8 m, corridor half-width 1.0-1.5 m), a robot at 0.25-0.3 m/s nominal, and people
placed so that, if nobody reacted, they would meet the robot on its path (the timing is jittered by
up to ±1 s). Scenario ``i`` of a suite draws from its own generator seeded by ``(seed, i)``, so a
suite is the same for the same seed, and its first scenarios do not change when ``count`` grows.

Families (the scenario name is ``<family>-<index>``):

* ``crossing``: one person crossing the path at 30-150° either way, 0.2-0.8 m/s.
* ``head-on``: one person walking down the path towards the robot, 0.2-0.6 m/s, offset ≤ 0.3 m.
* ``overtaken``: one person coming from 1-2 m behind, 0.15-0.35 m/s faster than the robot.
* ``overtaking``: a slower walker 1.2-2.5 m ahead (5-50 % of the robot's speed).
* ``multi``: two or three people at once, each from crossing / head-on / overtaken.
* ``group``: 2-4 people walking abreast (0.6-0.8 m apart), crossing or head-on.
* ``crowd``: 6-12 people moved by the social-force model (:mod:`viapath.sim.social_force`) across and
  along the corridor with staggered start times; precomputed and written as timed waypoints.
* ``hallway``: a walled hallway (walls 0.5 m outside the corridor) with 3-6 oncoming people, moved
  by the social-force model with the walls.
* ``paper``: the paper's three (behind, front, side): the first three exactly as in the paper, the
  rest with jittered speeds and offsets.
* ``slow-walker``: a 16-22 m corridor with a walker ahead at 0.15-0.25 m/s, a robot at 0.35-0.45 m/s and
  one to three people coming the other way (:func:`slow_walker`; not part of ``mixed``).
* ``static``: boxes, carts, pillars and doors on and beside the path, walls along the corridor,
  people among them (:func:`static`; not part of ``mixed``).
* ``eth-ucy``: real pedestrians (ETH/UCY replays) with a designated path placed across each of the
  five standard scenes (eth, hotel, univ, zara1, zara2) at many start times; see :func:`eth_ucy`.
* ``eth-ucy-react``: the same scenarios (same paths and start times for the same seed), with people who
  give way to the robot (``replay: {react: true}``, :mod:`viapath.sim.reactive`).
* ``eth-ucy-maps``: the same scenarios, and the ETH and hotel ones bring the authors' obstacle map
  (building walls, tram-stop shelter and pillars) as ``walls`` near the path (:func:`with_ewap_map`).

The suite ``mixed`` cycles through every synthetic family (index ``i`` → family ``i mod 9``).

Families are kept in a :class:`viapath.registry.Registry` (``FAMILIES``): each generator registers
itself by name where it is defined, a second one under a taken name is refused, and ``viapath
suite``/``bench`` take their list from it. A family registered from outside (``@FAMILIES.register``)
is a suite of its own; ``mixed`` stays the nine built-in ones, so its scenarios never change.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from viapath.registry import Registry
from viapath.sim.social_force import simulate_crowd
from viapath.static import box_edges, polygon_edges, segment_distances

_SAFE_DUMPER = getattr(yaml, "CSafeDumper", yaml.SafeDumper)  # libyaml's emitter where present

FAMILIES: Registry[Callable[[np.random.Generator, int], dict]] = Registry("scenario family")

# The five standard leave-one-out scenes (data README §1): (scene, file, seconds per row step).
ETH_UCY_SCENES = [
    ("eth", "biwi_eth.txt", 2.0 / 3.0),
    ("hotel", "biwi_hotel.txt", 0.4),
    ("univ", "students001.txt", 0.4),
    ("zara1", "crowds_zara01.txt", 0.4),
    ("zara2", "crowds_zara02.txt", 0.4),
    ("univ", "students003.txt", 0.4),
]
ETH_UCY_FOLDER = "eth_ucy_trajectron"


class SuiteError(ValueError):
    """A suite that cannot be generated (unknown name, bad count, missing data)."""


def suite_names() -> list[str]:
    return ["mixed", *FAMILIES.ordered(), "eth-ucy", "eth-ucy-react", "eth-ucy-maps"]


def data_root() -> Path:
    """Where the third-party data lives: ``$VIAPATH_DATA``, else ``../shared/data`` relative to the
    current folder or to the repository root (the first that exists)."""
    env = os.environ.get("VIAPATH_DATA")
    if env:
        return Path(env).expanduser()
    repo_root = Path(__file__).resolve().parents[3]
    for base in (Path.cwd(), repo_root):
        candidate = (base / ".." / "shared" / "data").resolve()
        if candidate.is_dir():
            return candidate
    return (Path.cwd() / ".." / "shared" / "data").resolve()


def generate_suite(name: str, count: int, seed: int = 0, data: Path | None = None, workers: int = 1) -> list[dict]:
    """``count`` scenario dicts of suite ``name`` (see :func:`suite_names`), deterministic per seed.

    ``workers`` > 1 generates the synthetic scenarios in that many processes (joblib/loky, whose
    workers the benchmark then reuses): each scenario has its own generator ``[seed, index]``, so
    the suite is the same (the social-force families made generation the longest part
    of a 1000-scenario benchmark)."""
    if name not in suite_names():
        raise SuiteError(f"unknown suite {name!r}; available: {', '.join(suite_names())}")
    if count < 1:
        raise SuiteError(f"count must be at least 1, got {count}")
    if name in ("eth-ucy", "eth-ucy-react", "eth-ucy-maps"):
        return eth_ucy(count, seed, data, react=name == "eth-ucy-react", maps=name == "eth-ucy-maps")
    families = SYNTHETIC_FAMILIES if name == "mixed" else (name,)
    # Worker processes know only the families this module registers (not ones registered from outside).
    if workers > 1 and count > 1 and all(FAMILIES.get(f).__module__ == __name__ for f in families):
        import joblib

        from viapath.bench.executors import local_processes

        chunks = [range(start, min(count, start + 25)) for start in range(0, count, 25)]
        parts = local_processes(workers)(joblib.delayed(_synthetic_scenarios)(name, seed, chunk) for chunk in chunks)
        return [scenario for part in parts for scenario in part]
    return _synthetic_scenarios(name, seed, range(count))


def _synthetic_scenarios(name: str, seed: int, indices) -> list[dict]:
    scenarios = []
    for index in indices:
        family = SYNTHETIC_FAMILIES[index % len(SYNTHETIC_FAMILIES)] if name == "mixed" else name
        family_index = index // len(SYNTHETIC_FAMILIES) if name == "mixed" else index
        rng = np.random.default_rng([seed, index])
        scenario = FAMILIES.get(family)(rng, family_index)
        scenario["name"] = f"{family}-{index:04d}"
        scenario["seed"] = int(seed)
        scenarios.append(_rounded(scenario))
    return scenarios


def write_suite(scenarios: list[dict], out_dir: Path) -> list[Path]:
    """Write one YAML file per scenario; replay files are written relative to ``out_dir`` (the loader
    resolves them against the scenario's folder), so ``viapath run`` works on any file."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    written = []
    for scenario in scenarios:
        scenario = dict(scenario)
        obstacles = []
        for item in scenario.get("obstacles", []):
            if "replay" in item:
                replay = dict(item["replay"])
                replay["file"] = os.path.relpath(Path(replay["file"]).resolve(), out_dir.resolve())
                item = {"replay": replay}
            obstacles.append(item)
        scenario["obstacles"] = obstacles
        path = out_dir / f"{scenario['name']}.yaml"
        path.write_text(yaml.dump(scenario, Dumper=_SAFE_DUMPER, sort_keys=False, default_flow_style=None, width=120))
        written.append(path)
    return written


# -- common pieces --------------------------------------------------------------------------------


def _base(rng: np.random.Generator, family: str, description: str) -> dict:
    length = float(rng.uniform(6.0, 8.0))
    speed = float(rng.uniform(0.25, 0.3))
    return {
        "name": family,
        "description": description,
        "robot": {"start": [0.0, 0.0], "heading": 0.0, "speed": speed, "radius": 0.25},
        "path": {"waypoints": [[0.0, 0.0], [length, 0.0]], "half_width": float(rng.uniform(1.0, 1.5))},
        "obstacles": [],
        "duration_s": float(np.ceil(2.5 * length / speed)),
    }


def _length(scenario) -> float:
    return scenario["path"]["waypoints"][1][0]


def _robot_speed(scenario) -> float:
    return scenario["robot"]["speed"]


def _crossing_person(rng, scenario) -> dict:
    length, speed = _length(scenario), _robot_speed(scenario)
    meet_x = rng.uniform(2.0, length - 2.0)
    meet_t = meet_x / speed + rng.uniform(-1.0, 1.0)
    angle = np.radians(rng.uniform(30.0, 150.0)) * rng.choice([-1.0, 1.0])
    walk = rng.uniform(0.2, 0.8)
    velocity = walk * np.array([np.cos(angle), np.sin(angle)])
    start = np.array([meet_x, 0.0]) - velocity * meet_t
    return {"start": start.tolist(), "velocity": velocity.tolist(), "radius": 0.25}


def _head_on_person(rng, scenario, lateral_m: float = 0.3) -> dict:
    """A person coming the other way within ``lateral_m`` of the path line."""
    length, speed = _length(scenario), _robot_speed(scenario)
    meet_x = rng.uniform(2.5, length - 1.5)
    walk = rng.uniform(0.2, 0.6)
    meet_t = meet_x / speed + rng.uniform(-1.0, 1.0)
    start = [meet_x + walk * meet_t, rng.uniform(-lateral_m, lateral_m)]
    return {"start": start, "velocity": [-walk, 0.0], "radius": 0.25}


def _overtaking_person(rng, scenario) -> dict:
    speed = _robot_speed(scenario)
    return {
        "start": [-rng.uniform(1.0, 2.0), rng.uniform(-0.2, 0.2)],
        "velocity": [speed + rng.uniform(0.15, 0.35), 0.0],
        "radius": 0.25,
    }


@FAMILIES.register("crossing")
def crossing(rng, index) -> dict:
    scenario = _base(rng, "crossing", "One person crosses the path at a random angle and speed.")
    scenario["obstacles"].append(_crossing_person(rng, scenario))
    return scenario


@FAMILIES.register("head-on")
def head_on(rng, index) -> dict:
    scenario = _base(rng, "head-on", "One person walks down the path towards the robot.")
    scenario["obstacles"].append(_head_on_person(rng, scenario))
    return scenario


@FAMILIES.register("overtaken")
def overtaken(rng, index) -> dict:
    scenario = _base(rng, "overtaken", "A faster person comes from behind along the path.")
    scenario["obstacles"].append(_overtaking_person(rng, scenario))
    return scenario


@FAMILIES.register("overtaking")
def overtaking(rng, index) -> dict:
    scenario = _base(rng, "overtaking", "A slower walker ahead on the path: the robot must pass it.")
    speed = _robot_speed(scenario)
    scenario["obstacles"].append(
        {
            "start": [rng.uniform(1.2, 2.5), rng.uniform(-0.2, 0.2)],
            "velocity": [speed * rng.uniform(0.05, 0.5), 0.0],
            "radius": 0.25,
        }
    )
    return scenario


@FAMILIES.register("multi")
def multi(rng, index) -> dict:
    scenario = _base(rng, "multi", "Two or three people at once: crossing, head-on or from behind.")
    makers = [_crossing_person, _head_on_person, _overtaking_person]
    for _ in range(int(rng.integers(2, 4))):
        scenario["obstacles"].append(makers[int(rng.integers(0, 3))](rng, scenario))
    return scenario


@FAMILIES.register("group")
def group(rng, index) -> dict:
    scenario = _base(rng, "group", "A group of 2-4 people walking abreast, crossing or head-on.")
    leader = _crossing_person(rng, scenario) if rng.random() < 0.5 else _head_on_person(rng, scenario)
    velocity = np.asarray(leader["velocity"])
    across = np.array([-velocity[1], velocity[0]]) / np.hypot(*velocity)
    spacing = rng.uniform(0.6, 0.8)
    size = int(rng.integers(2, 5))
    for k in range(size):
        shift = (k - (size - 1) / 2) * spacing
        start = np.asarray(leader["start"]) + shift * across
        scenario["obstacles"].append({"start": start.tolist(), "velocity": velocity.tolist(), "radius": 0.25})
    return scenario


def _timed_people(trajectory, keep_every: int, starts_at, radius=0.25) -> list[dict]:
    """Social-force output as obstacles with timed waypoints: a point every ``keep_every`` samples
    from when each person sets off to when they stop moving (standing still before and after)."""
    people = []
    times = trajectory.times_s
    for j in range(trajectory.positions.shape[1]):
        positions = trajectory.positions[:, j]
        moving = np.flatnonzero(np.hypot(*trajectory.velocities[:, j].T) > 1e-3)
        first = int(np.searchsorted(times, starts_at[j] - 1e-9))
        last = min(int(moving[-1]) + 1, len(times) - 1) if len(moving) else len(times) - 1
        picks = [k for k in range(first, last, keep_every) if k > 0] + [last]
        people.append(
            {
                "start": positions[0].tolist(),
                "waypoints": [positions[k].tolist() for k in picks],
                "times_s": [0.0] + [float(times[k]) for k in picks],
                "radius": radius,
            }
        )
    return people


@FAMILIES.register("crowd")
def crowd(rng, index) -> dict:
    scenario = _base(
        rng,
        "crowd",
        "A crowd moved by the social-force model (Helbing & Molnar 1995), "
        "crossing and walking along the corridor; precomputed, does not react to the robot.",
    )
    length = _length(scenario)
    n = int(rng.integers(6, 13))
    starts, routes = [], []
    for _ in range(n):
        if rng.random() < 0.65:  # crossing flow, from one side to the other
            side = rng.choice([-1.0, 1.0])
            x0, x1 = rng.uniform(0.5, length + 1.0, 2)
            starts.append([x0, side * rng.uniform(3.0, 6.0)])
            routes.append([[x1, -side * rng.uniform(3.5, 6.0)]])
        else:  # along the corridor, towards the robot
            starts.append([rng.uniform(length + 1.0, length + 6.0), rng.uniform(-1.5, 1.5)])
            routes.append([[-3.0, rng.uniform(-2.0, 2.0)], [-6.0, rng.uniform(-4.0, 4.0)]])
    start_times = rng.uniform(0.0, 15.0, n)
    speeds = rng.uniform(0.5, 1.1, n)
    trajectory = simulate_crowd(
        starts, routes, speeds, scenario["duration_s"], sample_dt_s=0.1, start_times_s=start_times
    )
    scenario["obstacles"] = _timed_people(trajectory, 5, start_times)
    return scenario


@FAMILIES.register("hallway")
def hallway(rng, index) -> dict:
    scenario = _base(rng, "hallway", "A walled hallway with oncoming people, moved by the social-force model.")
    length, half_width = _length(scenario), scenario["path"]["half_width"]
    wall_y = half_width + 0.5
    walls = [[[-3.0, wall_y], [length + 10.0, wall_y]], [[-3.0, -wall_y], [length + 10.0, -wall_y]]]
    n = int(rng.integers(3, 7))
    starts = [[rng.uniform(length + 1.0, length + 8.0), rng.uniform(-wall_y + 0.4, wall_y - 0.4)] for _ in range(n)]
    routes = [[[-2.5, rng.uniform(-wall_y + 0.4, wall_y - 0.4)]] for _ in range(n)]
    start_times = rng.uniform(0.0, 10.0, n)
    trajectory = simulate_crowd(
        starts,
        routes,
        rng.uniform(0.5, 1.1, n),
        scenario["duration_s"],
        sample_dt_s=0.1,
        walls=walls,
        start_times_s=start_times,
    )
    scenario["obstacles"] = _timed_people(trajectory, 5, start_times)
    scenario["walls"] = walls
    return scenario


@FAMILIES.register("paper")
def paper(rng, index) -> dict:
    """The paper's three experiments (§4, Fig. 8): robot 0.2 m/s, goal 5 m ahead, corridor ±1 m."""
    variant = index % 3
    exact = index < 3
    jitter = (lambda low, high: 0.0) if exact else (lambda low, high: float(rng.uniform(low, high)))
    scenario = {
        "name": "paper",
        "description": [
            "Paper Fig. 8 left: obstacle from behind.",
            "Paper Fig. 8 centre: obstacle head-on.",
            "Paper Fig. 8 right: obstacle crossing from the right side.",
        ][variant]
        + ("" if exact else " Speeds and offsets jittered."),
        "robot": {"start": [0.0, 0.0], "heading": 0.0, "speed": 0.2, "radius": 0.25},
        "path": {"waypoints": [[0.0, 0.0], [5.0, 0.0]], "half_width": 1.0},
        "duration_s": 60.0,
    }
    walk = 0.3 + jitter(-0.05, 0.05)
    if variant == 0:
        obstacle = {"start": [-1.0 + jitter(-0.3, 0.3), jitter(-0.1, 0.1)], "velocity": [walk, 0.0]}
    elif variant == 1:
        obstacle = {"start": [2.0 + jitter(-0.3, 0.5), jitter(-0.1, 0.1)], "velocity": [-walk, 0.0]}
    else:
        obstacle = {"start": [1.0 + jitter(-0.3, 0.3), -1.0 + jitter(-0.2, 0.2)], "velocity": [0.0, walk]}
    scenario["obstacles"] = [{**obstacle, "radius": 0.25}]
    return scenario


# The nine of ``mixed``, in its order (registered above in this order; checked in the tests).
SYNTHETIC_FAMILIES = FAMILIES.ordered()


# -- static geometry (registered after the nine of ``mixed``, which stay as they were) ----------------

STATIC_KINDS = ("box", "cart", "pillars", "door", "walls")


def _static_edges(scenario: dict) -> np.ndarray:
    """Every edge of the scene's boxes and polygons (M, 2, 2)."""
    edges = [box_edges(b["center"], b["size"], b.get("yaw", 0.0)) for b in scenario.get("boxes", [])]
    edges += [polygon_edges(p["points"]) for p in scenario.get("polygons", [])]
    return np.concatenate(edges) if edges else np.zeros((0, 2, 2))


def _walks_clear(person: dict, scenario: dict, clearance_m: float) -> bool:
    """Whether the person's straight walk over the whole run keeps ``clearance_m`` from every box and polygon."""
    start = np.asarray(person["start"], dtype=float)
    end = start + np.asarray(person["velocity"], dtype=float) * scenario["duration_s"]
    return bool(
        (segment_distances(start[None], end[None], _static_edges(scenario)) >= person["radius"] + clearance_m).all()
    )


def _person_round_static(rng, scenario: dict, draw: Callable, tries: int = 50) -> dict | None:
    """A person from ``draw(rng, scenario)`` whose walk passes the boxes and polygons (people walk round carts,
    not through them: replayed people do not avoid anything); None when ``tries`` draws all meet one."""
    for _ in range(tries):
        person = draw(rng, scenario)
        if _walks_clear(person, scenario, 0.1):
            return person
    return None


@FAMILIES.register("static")
def static(rng, index) -> dict:
    """Static geometry on and beside the path, people among it (kind ``index mod 5``, :data:`STATIC_KINDS`):

    * ``box``: a box of 0.3-0.6 m on the path (offset ≤ 0.2 m), room to pass on both sides; a crossing
      person in half of them;
    * ``cart``: a 0.4-0.6 x 0.8-1.2 m cart at any yaw beside or on the path, a person head-on;
    * ``pillars``: two or three pillars (octagons, 0.15-0.3 m radius) within 0.6 m of the path;
    * ``door``: walls along the corridor and a closed door across it 3-5 m ahead that opens at 8-20 s
      (in a third of them it never opens: the goal is unreachable, ``description`` says so);
    * ``walls``: walls 0.05-0.4 m outside the corridor on both sides, a person head-on.

    Every person walks clear of the boxes and polygons (redrawn until so, left out after 50 tries).
    """
    kind = STATIC_KINDS[index % len(STATIC_KINDS)]
    scenario = _base(rng, "static", f"Static geometry: {kind}.")
    length, half_width = _length(scenario), scenario["path"]["half_width"]
    if kind == "box":
        size = float(rng.uniform(0.3, 0.6))
        scenario["boxes"] = [
            {
                "center": [float(rng.uniform(2.5, length - 2.0)), float(rng.uniform(-0.2, 0.2))],
                "size": [size, float(rng.uniform(0.3, 0.6))],
                "yaw": float(rng.uniform(-0.5, 0.5)),
            }
        ]
        if rng.random() < 0.5:
            scenario["obstacles"].append(_person_round_static(rng, scenario, _crossing_person))
    elif kind == "cart":
        on_path = rng.random() < 0.5
        centre = [
            float(rng.uniform(2.5, length - 2.0)),
            float(rng.uniform(-0.15, 0.15)) if on_path else float(rng.choice([-1, 1]) * (half_width - 0.1)),
        ]
        scenario["boxes"] = [
            {
                "center": centre,
                "size": [float(rng.uniform(0.8, 1.2)), float(rng.uniform(0.4, 0.6))],
                "yaw": float(rng.uniform(-np.pi, np.pi)) if on_path else 0.0,
            }
        ]
        # Anywhere across the corridor, so that a lane beside the cart is drawn in a few tries.
        lane = max(half_width - 0.25, 0.3)
        scenario["obstacles"].append(
            _person_round_static(rng, scenario, lambda rng, scenario: _head_on_person(rng, scenario, lane))
        )
    elif kind == "pillars":
        angles = np.linspace(0.0, 2 * np.pi, 9)[:-1]
        xs = np.sort(rng.uniform(2.0, length - 1.5, int(rng.integers(2, 4))))
        xs = xs[0] + np.concatenate([[0.0], np.cumsum(np.maximum(np.diff(xs), 1.2))])
        pillars = []
        for x in xs[xs < length - 1.0]:
            r, y = float(rng.uniform(0.15, 0.3)), float(rng.uniform(-0.6, 0.6))
            if abs(y) < r + 0.45 and half_width - abs(y) - r < 0.45:  # leave a way round inside the corridor
                y = 0.0
            pillars.append({"points": (np.c_[x + r * np.cos(angles), y + r * np.sin(angles)]).tolist()})
        scenario["polygons"] = pillars
        if rng.random() < 0.5:
            scenario["obstacles"].append(_person_round_static(rng, scenario, _crossing_person))
    elif kind == "door":
        wall_y = half_width + 0.05
        door_x = float(rng.uniform(3.0, min(5.0, length - 1.5)))
        opens = rng.random() >= 1 / 3
        door: dict[str, Any] = {"points": [[door_x, -wall_y], [door_x, wall_y]]}
        if opens:
            door["until_s"] = float(rng.uniform(8.0, 20.0))
        else:
            scenario["description"] = "Static geometry: door, closed for the whole run (the goal is unreachable)."
        scenario["walls"] = [[[-3.0, wall_y], [length + 3.0, wall_y]], [[-3.0, -wall_y], [length + 3.0, -wall_y]], door]
    else:
        wall_y = half_width + float(rng.uniform(0.05, 0.4))
        scenario["walls"] = [[[-3.0, wall_y], [length + 3.0, wall_y]], [[-3.0, -wall_y], [length + 3.0, -wall_y]]]
        scenario["obstacles"].append(_head_on_person(rng, scenario))
    scenario["obstacles"] = [person for person in scenario["obstacles"] if person is not None]
    return scenario


# -- passing a slow walker (registered after ``mixed``'s nine, which stay as they were) ----------------


@FAMILIES.register("slow-walker")
def slow_walker(rng, index) -> dict:
    """A long corridor with a slow walker ahead and people coming the other way, with room to pass:

    corridor 16-22 m long, half-width 1.1-1.4 m; robot 0.35-0.45 m/s nominal; the walker 2-4 m ahead
    at 0.15-0.25 m/s (within 0.3 m of the path); one to three people walking the other way at
    0.4-0.9 m/s, met at staggered times, each on either side of the path. Beside the walker there is
    always 0.55 m or more to the corridor's edge, so a robot of 0.25 m radius (0.05 m margin) can pass inside it.
    """
    length = float(rng.uniform(16.0, 22.0))
    speed = float(rng.uniform(0.35, 0.45))
    half_width = float(rng.uniform(1.1, 1.4))
    walker_y = float(rng.uniform(-0.3, 0.3))
    scenario: dict[str, Any] = {
        "name": "slow-walker",
        "description": "A slow walker ahead in a long corridor, people coming the other way: pass, do not trail.",
        "robot": {"start": [0.0, 0.0], "heading": 0.0, "speed": speed, "radius": 0.25},
        "path": {"waypoints": [[0.0, 0.0], [length, 0.0]], "half_width": half_width},
        "obstacles": [
            {
                "start": [float(rng.uniform(2.0, 4.0)), walker_y],
                "velocity": [float(rng.uniform(0.15, 0.25)), 0.0],
                "radius": 0.25,
            }
        ],
        "duration_s": float(np.ceil(2.0 * length / speed)),
    }
    for _ in range(int(rng.integers(1, 4))):
        walk = float(rng.uniform(0.4, 0.9))
        meet_x = float(rng.uniform(4.0, length - 2.0))
        meet_t = meet_x / speed + float(rng.uniform(-3.0, 3.0))
        side = float(rng.choice([-1.0, 1.0]))
        scenario["obstacles"].append(
            {
                "start": [meet_x + walk * meet_t, side * float(rng.uniform(0.3, half_width - 0.3))],
                "velocity": [-walk, 0.0],
                "radius": 0.25,
            }
        )
    return scenario


# -- ETH/UCY ---------------------------------------------------------------------------------------


@lru_cache(maxsize=8)
def _scene_samples(file: str, dt_s: float):
    """All (time, x, y) samples of a trajectory file, as one array."""
    table = np.loadtxt(file, ndmin=2)
    return np.column_stack([table[:, 0] / 10.0 * dt_s, table[:, 2], table[:, 3]])


def eth_ucy(
    count: int,
    seed: int = 0,
    data: Path | None = None,
    path_length_m: float = 6.0,
    robot_speed_mps: float = 0.3,
    duration_s: float = 40.0,
    react: bool = False,
    maps: bool = False,
) -> list[dict]:
    """Designated paths across the five ETH/UCY scenes at many start times (scene ``i mod 5``; univ
    alternates between students001 and students003).

    For each scenario: a start time is drawn; the path's midpoint is a position some person occupies
    during the episode (so the path goes where people walk), its direction is random; both ends lie
    inside the scene's central 90 % box, nobody is within 1 m of the robot's start at the start time,
    and at least one person comes within 2 m of the path during the episode. Every pedestrian of the
    file is replayed (``replay`` item, docs/design.md §4); they do not react to the robot, unless ``react``
    (then the names read ``eth-ucy-react-<scene>-<index>`` and the scenarios are otherwise the same).
    With ``maps``, the ETH and hotel scenarios also bring their obstacle map (:func:`with_ewap_map`).
    """
    root = Path(data) if data is not None else data_root()
    folder = root / ETH_UCY_FOLDER
    if not folder.is_dir():
        raise SuiteError(
            f"ETH/UCY data not found at {folder}; set VIAPATH_DATA to the folder holding "
            f"{ETH_UCY_FOLDER}/ (see the data README)"
        )
    scenarios = []
    for index in range(count):
        scene_slot = index % 5
        if scene_slot == 2:  # univ: alternate its two files
            scene, file, dt = ETH_UCY_SCENES[2] if (index // 5) % 2 == 0 else ETH_UCY_SCENES[5]
        else:
            scene, file, dt = ETH_UCY_SCENES[scene_slot]
        rng = np.random.default_rng([seed, index, 7])
        file_path = (folder / file).resolve()
        if not file_path.exists():
            raise SuiteError(f"{file_path}: ETH/UCY file missing")
        samples = _scene_samples(str(file_path), dt)
        ends_clear = _ends_clear_of_map(root, file) if maps else None
        scenario = _place_path(rng, samples, path_length_m, robot_speed_mps, duration_s, ends_clear=ends_clear)
        if scenario is None:  # pragma: no cover - every standard scene has room
            raise SuiteError(f"could not place a path in {file} after many tries")
        start_s, waypoints = scenario
        replay = {"file": str(file_path), "dt_s": dt, "start_s": start_s, "offset": [0.0, 0.0], "radius": 0.25}
        if react:
            replay["react"] = True
        scenarios.append(
            _rounded(
                {
                    "name": f"eth-ucy-{'react-' if react else ''}{scene}-{index:04d}",
                    "description": f"ETH/UCY scene {scene} ({file}, {dt:.3f} s per row) replayed from {start_s:.1f} s; "
                    + ("the people give way to the robot." if react else "the people do not react to the robot."),
                    "robot": {
                        "start": waypoints[0],
                        "heading": float(
                            np.arctan2(waypoints[1][1] - waypoints[0][1], waypoints[1][0] - waypoints[0][0])
                        ),
                        "speed": robot_speed_mps,
                        "radius": 0.25,
                    },
                    "path": {"waypoints": waypoints, "half_width": 1.0},
                    "obstacles": [{"replay": replay}],
                    "duration_s": duration_s,
                    "seed": int(seed),
                }
            )
        )
        if maps:
            scenarios[-1] = with_ewap_map(scenarios[-1], root)
    return scenarios


ETH_UCY_MAP_MARGIN_M = 1.0  # m; map geometry kept this far beyond the corridor's bounding box
# m; with a map, the path's ends keep this far from it (robot radius 0.25 m + 0.1 m): a robot does not start
# in a wall, a goal is not inside a pillar. A path may still pass closer between its ends (go round, as
# in the static family).
ETH_UCY_MAP_END_CLEARANCE_M = 0.35


def _ends_clear_of_map(data: Path, file: str) -> Callable | None:
    """With a map for ``file``: whether points (K, 2) all lie outside its obstacles and at least
    :data:`ETH_UCY_MAP_END_CLEARANCE_M` from their outlines; None without one."""
    from viapath.io.ewap_map import sequence_folder
    from viapath.static import point_segment_distances

    folder = sequence_folder(data, file)
    if folder is None or not folder.is_dir():
        return None
    obstacles = _ewap_map(str(folder))
    segments = obstacles.segments()
    return lambda points: bool(
        not obstacles.contains(points).any()
        and (point_segment_distances(points, segments).min(axis=1) >= ETH_UCY_MAP_END_CLEARANCE_M).all()
    )


@lru_cache(maxsize=4)
def _ewap_map(folder: str):
    from viapath.io.ewap_map import read_obstacle_map

    return read_obstacle_map(folder)


def with_ewap_map(scenario: dict, data: Path, margin_m: float = ETH_UCY_MAP_MARGIN_M) -> dict:
    """An ``eth-ucy`` scenario with its scene's obstacle map (``eth_ewap_original/<sequence>/map.png`` +
    ``H.txt``, :mod:`viapath.io.ewap_map`) as ``walls``: the outlines' parts inside the path's bounding
    box widened by the corridor's half-width and ``margin_m``; named ``eth-ucy-maps-...``. A scene without
    a map (the UCY ones) only gets the name."""
    from viapath.io.ewap_map import sequence_folder

    (replay,) = (item["replay"] for item in scenario["obstacles"])
    scenario = {**scenario, "name": scenario["name"].replace("eth-ucy-", "eth-ucy-maps-", 1)}
    folder = sequence_folder(data, replay["file"])
    if folder is None:
        return scenario
    if not folder.is_dir():
        raise SuiteError(f"{folder}: ETH obstacle map missing (map.png and H.txt; see the data README)")
    waypoints = np.asarray(scenario["path"]["waypoints"], dtype=float)
    reach = scenario["path"]["half_width"] + margin_m
    walls = _ewap_map(str(folder)).walls_in_box(waypoints.min(axis=0) - reach, waypoints.max(axis=0) + reach)
    scenario["walls"] = _rounded([{"points": wall.tolist()} for wall in walls])
    scenario["description"] += f" Obstacle map of {folder.name} near the path (wall polylines: {len(walls)})."
    return scenario


def _place_path(rng, samples, length, speed, duration, tries: int = 500, ends_clear: Callable | None = None):
    times, xy = samples[:, 0], samples[:, 1:]
    low, high = np.percentile(xy, 5, axis=0), np.percentile(xy, 95, axis=0)
    t_first, t_last = times.min(), times.max()
    for _ in range(tries):
        start_s = float(rng.uniform(t_first, max(t_first, t_last - duration)))
        window = (times >= start_s) & (times <= start_s + duration)
        if window.sum() < 2:
            continue
        centre = xy[rng.choice(np.flatnonzero(window))]
        angle = rng.uniform(-np.pi, np.pi)
        direction = np.array([np.cos(angle), np.sin(angle)])
        a, b = centre - direction * length / 2, centre + direction * length / 2
        if not (np.all(a >= low) and np.all(a <= high) and np.all(b >= low) and np.all(b <= high)):
            continue
        # Nobody within 1 m of the start when the episode begins (within one row step of it).
        now = np.abs(times - start_s) <= 0.7
        if np.any(np.hypot(*(xy[now] - a).T) < 1.0):
            continue
        # Someone comes within 2 m of the path during the episode.
        rel = xy[window] - a
        along = np.clip(rel @ direction, 0.0, length)
        gap = np.hypot(*(rel - along[:, None] * direction).T)
        if not np.any(gap < 2.0):
            continue
        if ends_clear is not None and not ends_clear(np.array([a, b])):
            continue
        return start_s, [a.tolist(), b.tolist()]
    return None


def _rounded(value):
    """Round floats to mm / ms so the YAML stays readable (and identical across platforms)."""
    if isinstance(value, float):
        return round(value, 4)
    if isinstance(value, (np.floating,)):
        return round(float(value), 4)
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, dict):
        return {k: _rounded(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_rounded(v) for v in value]
    return value
