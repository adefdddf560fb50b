"""Long fuzz run of the guarded entry (issue 12): the CI properties of tests/robustness/test_fuzz_entry.py
on many more generated observations, counting instead of stopping at the first failure.

Usage: python benchmarks/fuzz_entry.py [--cases 100000] [--planners all] [--laser-cases 5000]
                                       [--input-cases 300] [--construction-cases 300] [--ros-cases 300] [--seed 0] [--json]

Observations come from the same hypothesis strategy as the tests (tests/robustness/_fuzz.py:
NaN / inf / negative / huge fields and wrong shapes mixed into valid ones, five cycles per
hypothesis example), split evenly over the planners; each planner sees its share as one stream of
cycles. Per planner it prints: observations, how many were refused with the documented
ObservationError, how the guard answered (``guard-stop``, ``guard-brake``, repaired fields, planned
normally), and the violations, which must all be 0: another exception, a command not finite or
outside the limits, a command closing on an obstacle within stopping distance (independent
brute-force roll-out). The laser part feeds generated scan sets (0/NaN/inf ranges, wrong lengths,
a scanner missing) through LaserPerception.process into the viapath planner. The input part feeds
hostile scenario texts (alias bombs, deep nesting, huge integer literals, far coordinates:
tests/robustness/_hostile.py) to the scenario and preset readers (each must be refused with a short
message naming the file and field; the slowest refusal is reported); the construction part builds
planners from bad descriptions (refused) and from option values inside their bounds (must plan).
The ROS part drives the ROS 2 node's cycle (viapath.ros2.core.PlannerCore, no rclpy) with generated episodes: an honest base
and odometry that starts to lie (twist beyond the limits, never commanded, not borne out by the pose,
pose and heading jumps, quaternions that are no rotation), malformed scans (first ones included) and
empty or bad paths; violations: an exception, a command not finite or outside the limits, a command
faster than one cycle's braking from the last command while the status reports an odometry fault
or no path.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, seed, settings

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "robustness"))

from _fuzz import observation_batches, scan_sets
from _helpers import fresh, inside_limits, moves_towards_close_obstacle

from viapath.observation import Observation, ObservationError, RobotState
from viapath.planning import available_planners

BATCH = 5


def classify(planner, observation, counts: Counter, examples: list) -> None:
    counts["observations"] += 1
    if isinstance(observation, ObservationError):
        counts["refused (ObservationError)"] += 1
        return
    try:
        decision = planner.plan(observation)
    except ObservationError:
        counts["refused (ObservationError)"] += 1
        return
    except Exception as error:
        counts["VIOLATION other exception"] += 1
        examples.append(f"{type(error).__name__}: {error}")
        return
    status = decision.plan.status
    if status in ("guard-stop", "guard-brake"):
        counts[status] += 1
    elif decision.plan.extras.get("guard"):
        counts["planned with repaired fields"] += 1
    else:
        counts["planned normally"] += 1
    command = decision.command
    if not inside_limits(command, planner.limits):
        counts["VIOLATION bad command"] += 1
        examples.append(f"{command} ({status})")
    elif moves_towards_close_obstacle(command, observation) is not None:
        counts["VIOLATION closes on obstacle"] += 1
        examples.append(f"{command} ({status}) at {observation.robot}")


def fuzz_planner(name: str, cases: int, base_seed: int) -> dict:
    planner = fresh(name)
    counts: Counter = Counter()
    examples: list[str] = []

    @seed(base_seed)
    @settings(
        max_examples=max(1, cases // BATCH), deadline=None, database=None, suppress_health_check=list(HealthCheck)
    )
    @given(observation_batches(BATCH))
    def run(batch):
        for observation in batch:
            classify(planner, observation, counts, examples)

    started = time.perf_counter()
    cpu = time.process_time()
    run()
    return {
        "planner": name,
        **dict(counts),
        "wall_s": time.perf_counter() - started,
        "cpu_s": time.process_time() - cpu,
        "violation_examples": examples[:5],
    }


def fuzz_laser(cases: int, base_seed: int) -> dict:
    from viapath.perception.laser import LaserPerception

    perception = LaserPerception()
    perception.reset(np.random.default_rng(base_seed))
    counts_beams = tuple(s.beam_count for s in perception.scanners)
    planner = fresh("viapath")
    counts: Counter = Counter()
    examples: list[str] = []
    clock = {"t": 0.0}

    @seed(base_seed)
    @settings(max_examples=cases, deadline=None, database=None, suppress_health_check=list(HealthCheck))
    @given(scan_sets(counts_beams))
    def run(scans):
        clock["t"] += 0.1
        pose = np.array([0.5 * np.sin(clock["t"]), 0.0, 0.1])
        counts["scan sets"] += 1
        try:
            obstacles = perception.process(clock["t"], pose, scans)
        except ObservationError:
            counts["refused (ObservationError)"] += 1
            return
        except Exception as error:
            counts["VIOLATION perception exception"] += 1
            examples.append(f"{type(error).__name__}: {error}")
            return
        if not (np.isfinite(obstacles.positions).all() and np.isfinite(obstacles.velocities).all()):
            counts["VIOLATION non-finite track"] += 1
        classify(
            planner, Observation(clock["t"], RobotState(pose[:2], pose[2], 0.2, 0.0, 0.25), obstacles), counts, examples
        )

    started = time.perf_counter()
    cpu = time.process_time()
    run()
    return {
        "planner": "laser->viapath",
        **dict(counts),
        "wall_s": time.perf_counter() - started,
        "cpu_s": time.process_time() - cpu,
        "violation_examples": examples[:5],
    }


def fuzz_inputs(cases: int, base_seed: int) -> dict:
    """Hostile scenario text (tests/robustness/_hostile.py: alias bombs, deep nesting, too many nodes,
    integer literals of thousands of digits, coordinates near the float limit) through the scenario and
    preset readers: each must be refused with their error, a short message naming the file (and the
    field), quickly."""
    from _hostile import far_coordinates, hostile_yaml, long_integers
    from hypothesis import strategies as st

    from viapath.presets import PresetError, parse_preset
    from viapath.scenarios import ScenarioError
    from viapath.scenarios.loader import _parse

    counts: Counter = Counter()
    examples: list[str] = []
    slowest = [0.0, 0.0]  # wall, CPU
    cases_strategy = st.one_of(hostile_yaml().map(lambda text: (text, None)), long_integers(), far_coordinates())

    @seed(base_seed)
    @settings(max_examples=cases, deadline=None, database=None, suppress_health_check=list(HealthCheck))
    @given(cases_strategy)
    def run(case):
        text, field = case
        counts["inputs"] += 1
        for reader, expected in (
            (lambda: _parse(text, "s.yaml", base_dir=None), ScenarioError),
            (lambda: parse_preset(text, "s.yaml"), PresetError),
        ):
            started, cpu = time.perf_counter(), time.process_time()
            try:
                reader()
            except expected as error:
                message = str(error)
                if not message.startswith("s.yaml") or len(message) > 600:
                    counts["VIOLATION message unclear or long"] += 1
                    examples.append(message[:200])
                elif field is not None and expected is ScenarioError and f": {field}: " not in message:
                    counts["VIOLATION field not named"] += 1
                    examples.append(f"{field}: {message[:200]}")
                else:
                    counts["refused"] += 1
            except Exception as error:
                counts["VIOLATION other exception"] += 1
                examples.append(f"{type(error).__name__}: {str(error)[:200]}")
            else:
                counts["VIOLATION accepted"] += 1
            slowest[0] = max(slowest[0], time.perf_counter() - started)
            slowest[1] = max(slowest[1], time.process_time() - cpu)

    started = time.perf_counter()
    run()
    return {
        "planner": "hostile inputs",
        **dict(counts),
        "slowest_refusal_s": slowest[0],
        "slowest_refusal_cpu_s": slowest[1],
        "wall_s": time.perf_counter() - started,
        "violation_examples": examples[:5],
    }


def fuzz_construction(cases: int, base_seed: int) -> dict:
    """Planners built from generated descriptions and options: a bad robot radius, nominal speed or
    motion limit must be refused (OptionError naming it); option values inside their bounds must build a
    planner whose cycles give finite commands inside the limits (or be refused by the step cross-check)."""
    import math

    from _helpers import LIMITS, corridor, robot
    from _hostile import option_values
    from hypothesis import strategies as st

    from viapath.limits import LIMIT_BOUNDS
    from viapath.observation import MotionLimits, Obstacles
    from viapath.options import OptionError
    from viapath.planning import make_planner, planner_class

    bad = st.sampled_from([math.nan, math.inf, -math.inf, 0.0, -1.0, 1e-9, 1e308, "x", None])
    counts: Counter = Counter()
    examples: list[str] = []
    slowest = [0.0]
    obstacles = Obstacles(
        np.array([[1.2, 0.1], [2.0, -0.4], [0.8, 0.9]]),
        np.array([[-0.4, 0.0], [0.0, 0.3], [0.1, -0.2]]),
        np.full(3, 0.3),
    )

    @seed(base_seed)
    @settings(max_examples=cases, deadline=None, database=None, suppress_health_check=list(HealthCheck))
    @given(st.sampled_from(available_planners()), st.sampled_from(["radius", "speed", "limits", "options"]), st.data())
    def run(name, kind, data):
        counts["planners built"] += 1
        kwargs = {"nominal_speed_mps": 0.2, "limits": LIMITS, "robot_radius_m": 0.25}
        if kind == "radius":
            kwargs["robot_radius_m"] = data.draw(bad.filter(lambda r: r != 1e-9))  # a tiny radius is a radius
        elif kind == "speed":
            kwargs["nominal_speed_mps"] = data.draw(bad)
        elif kind == "limits":
            field = data.draw(st.sampled_from(sorted(LIMIT_BOUNDS)))
            kwargs["limits"] = MotionLimits(**{**LIMITS.__dict__, field: data.draw(bad)})
        else:
            kwargs["options"] = data.draw(option_values(planner_class(name).options))
        try:
            planner = make_planner(name, corridor(), **kwargs)
        except OptionError as error:
            if kind == "options" and "step" not in str(error):
                counts["VIOLATION option inside its bounds refused"] += 1
                examples.append(str(error)[:200])
            else:
                counts["refused (OptionError)"] += 1
            return
        except Exception as error:
            counts["VIOLATION other exception"] += 1
            examples.append(f"{type(error).__name__}: {str(error)[:200]}")
            return
        if kind != "options":
            counts["VIOLATION bad description accepted"] += 1
            examples.append(f"{name} {kind} {kwargs}")
            return
        started = time.perf_counter()
        try:
            for t in range(3):
                decision = planner.plan(Observation(0.1 * t, robot(x=0.02 * t), obstacles))
                if not inside_limits(decision.command, planner.limits):
                    counts["VIOLATION bad command"] += 1
                    examples.append(f"{name} {decision.command}")
                    return
        except Exception as error:
            counts["VIOLATION other exception"] += 1
            examples.append(f"{name} {type(error).__name__}: {str(error)[:200]}")
            return
        slowest[0] = max(slowest[0], (time.perf_counter() - started) / 3)
        counts["planned with generated options"] += 1

    started = time.perf_counter()
    run()
    return {
        "planner": "construction",
        **dict(counts),
        "slowest_cycle_s": slowest[0],
        "wall_s": time.perf_counter() - started,
        "violation_examples": examples[:5],
    }


def fuzz_ros(cases: int, base_seed: int) -> dict:
    """Generated hostile episodes through the ROS 2 node's cycle logic (see the module notes)."""
    import math

    from hypothesis import strategies as st

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "ros2"))
    from test_ros2_hostile import DT, FRAMES, SCANNERS, STEP, Robot, make_core

    counts: Counter = Counter()
    examples: list[str] = []
    number = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.floats(-2.0, 2.0))
    events = st.lists(
        st.one_of(
            st.tuples(st.just("honest")),
            st.tuples(st.just("twist"), number, number),
            st.tuples(st.just("jump"), number, number, number),
            st.tuples(st.just("quaternion"), st.tuples(number, number, number, number)),
            st.tuples(st.just("scan"), st.integers(0, 2000), number, number, number),
            st.tuples(st.just("path"), st.lists(st.tuples(number, number), max_size=4)),
        ),
        min_size=5,
        max_size=25,
    )

    @seed(base_seed)
    @settings(max_examples=cases, deadline=None, database=None, suppress_health_check=list(HealthCheck))
    @given(events, st.sampled_from(["urg04lx", "from_message"]))
    def run(episode, geometry):
        core = make_core(scan_geometry=geometry)
        robot = Robot(people=[(2.0, 0.3)])
        t = 1.0
        counts["episodes"] += 1
        for event in episode:
            kind = event[0]
            odom = [robot.x, robot.y, robot.heading, robot.v, robot.w]
            quaternion = (0.0, 0.0, math.sin(0.5 * robot.heading), math.cos(0.5 * robot.heading))
            if kind == "twist":
                odom[3], odom[4] = event[1], event[2]
            elif kind == "jump":
                odom[0], odom[1], odom[2] = odom[0] + event[1], odom[1] + event[2], odom[2] + event[3]
                quaternion = None
            elif kind == "quaternion":
                quaternion = event[1]
            try:
                if quaternion is None:
                    core.on_odometry(t, t, "odom", *odom)
                else:
                    core.on_odometry_quaternion(t, t, "odom", odom[0], odom[1], quaternion, odom[3], odom[4])
                for i, (s, ranges) in enumerate(zip(SCANNERS, robot.scans(), strict=True)):
                    if kind == "scan" and i == 0:
                        beams, increment, low, high = event[1:]
                        core.on_scan(i, t, t, FRAMES[i], s.angle_min_rad, increment, np.full(beams, 2.0), low, high)
                    else:
                        core.on_scan(i, t, t, FRAMES[i], s.angle_min_rad, s.angle_increment_rad, ranges)
                if kind == "path":
                    core.on_path("odom", np.array(event[1], dtype=float).reshape(-1, 2))
                before = core.last_command
                result = core.cycle(t)
            except Exception as error:
                counts["VIOLATION exception"] += 1
                examples.append(f"{kind}: {type(error).__name__}: {error}")
                return
            counts["cycles"] += 1
            c = result.command
            lim = core.limits
            if not (
                math.isfinite(c.speed_mps)
                and math.isfinite(c.turn_rate_radps)
                and 0.0 <= c.speed_mps <= lim.max_speed_mps
                and abs(c.turn_rate_radps) <= lim.max_turn_rate_radps
            ):
                counts["VIOLATION bad command"] += 1
                examples.append(f"{kind}: {c}")
            faults = [
                r for r in result.reasons if r.startswith(("odometry fault", "no designated path", "designated path"))
            ]
            if faults:
                counts["braking for " + faults[0].split(":")[0]] += 1
                if c.speed_mps > max(0.0, before.speed_mps - STEP) + 1e-9:
                    counts["VIOLATION not braking on a fault"] += 1
                    examples.append(f"{kind}: {c} after {before} ({faults[0]})")
            robot.drive(c)
            t += DT
        counts["odometry refused"] += sum(core.odom_refused.values())
        counts["scans refused"] += sum(sum(h.refused.values()) for h in core.health)
        counts["paths refused"] += core.paths_refused

    started = time.perf_counter()
    cpu = time.process_time()
    run()
    return {
        "planner": "ros2 node cycle",
        **dict(counts),
        "wall_s": time.perf_counter() - started,
        "cpu_s": time.process_time() - cpu,
        "violation_examples": examples[:5],
    }


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=100_000, help="observations in total, over the planners")
    parser.add_argument("--planners", default="all")
    parser.add_argument("--laser-cases", type=int, default=5_000)
    parser.add_argument("--input-cases", type=int, default=300, help="hostile scenario/preset texts")
    parser.add_argument("--construction-cases", type=int, default=300, help="generated planner constructions")
    parser.add_argument("--ros-cases", type=int, default=300, help="generated episodes through the ROS 2 node's cycle")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    names = available_planners() if args.planners == "all" else args.planners.split(",")
    results = []
    for name in names:
        results.append(fuzz_planner(name, args.cases // len(names), args.seed))
        if not args.json:
            print(json.dumps(results[-1]), flush=True)
    if args.laser_cases:
        results.append(fuzz_laser(args.laser_cases, args.seed))
        if not args.json:
            print(json.dumps(results[-1]), flush=True)
    for count, fuzz in ((args.input_cases, fuzz_inputs), (args.construction_cases, fuzz_construction)):
        if count:
            results.append(fuzz(count, args.seed))
            if not args.json:
                print(json.dumps(results[-1]), flush=True)
    if args.ros_cases:
        results.append(fuzz_ros(args.ros_cases, args.seed))
        if not args.json:
            print(json.dumps(results[-1]), flush=True)
    total = sum(r.get("observations", 0) for r in results)
    violations = sum(v for r in results for k, v in r.items() if k.startswith("VIOLATION"))
    summary = {"observations": total, "violations": violations, "results": results}
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        print(f"total: {total} observations, {violations} violations")
    return 0 if violations == 0 else 1


if __name__ == "__main__":
    raise SystemExit(main())
