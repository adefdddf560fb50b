"""Long fuzz run of the guarded entry (issue 12): the CI properties of tests/robustness/test_fuzz_entry.py
on many more generated observations, counting instead of stopping at the first failure.

Usage: python benchmarks/fuzz_entry.py [--cases 100000] [--planners all] [--laser-cases 5000]
                                       [--seed 0] [--json]

Observations come from the same hypothesis strategy as the tests (tests/robustness/_fuzz.py:
NaN / inf / negative / huge fields and wrong shapes mixed into valid ones, five cycles per
hypothesis example), split evenly over the planners; each planner sees its share as one stream of
cycles. Per planner it prints: observations, how many were refused with the documented
ObservationError, how the guard answered (``guard-stop``, ``guard-brake``, repaired fields, planned
normally), and the violations, which must all be 0: another exception, a command not finite or
outside the limits, a command closing on an obstacle within stopping distance (independent
brute-force roll-out). The laser part feeds generated scan sets (0/NaN/inf ranges, wrong lengths,
a scanner missing) through LaserPerception.process into the viapath planner.
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

from _fuzz import observation_batches, scan_sets  # noqa: E402
from _helpers import fresh, inside_limits, moves_towards_close_obstacle  # noqa: E402

from viapath.observation import Observation, ObservationError, RobotState  # noqa: E402
from viapath.planning import available_planners  # noqa: E402

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
    except Exception as error:  # noqa: BLE001 - counted
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
    @settings(max_examples=max(1, cases // BATCH), deadline=None, database=None,
              suppress_health_check=list(HealthCheck))
    @given(observation_batches(BATCH))
    def run(batch):
        for observation in batch:
            classify(planner, observation, counts, examples)

    started = time.perf_counter()
    cpu = time.process_time()
    run()
    return {"planner": name, **dict(counts), "wall_s": time.perf_counter() - started,
            "cpu_s": time.process_time() - cpu, "violation_examples": examples[:5]}


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
        except Exception as error:  # noqa: BLE001 - counted
            counts["VIOLATION perception exception"] += 1
            examples.append(f"{type(error).__name__}: {error}")
            return
        if not (np.isfinite(obstacles.positions).all() and np.isfinite(obstacles.velocities).all()):
            counts["VIOLATION non-finite track"] += 1
        classify(planner, Observation(clock["t"], RobotState(pose[:2], pose[2], 0.2, 0.0, 0.25), obstacles),
                 counts, examples)

    started = time.perf_counter()
    cpu = time.process_time()
    run()
    return {"planner": "laser->viapath", **dict(counts), "wall_s": time.perf_counter() - started,
            "cpu_s": time.process_time() - cpu, "violation_examples": examples[:5]}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=100_000, help="observations in total, over the planners")
    parser.add_argument("--planners", default="all")
    parser.add_argument("--laser-cases", type=int, default=5_000)
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
