"""Fuzzing the guarded entry (issue 12): every registered planner, navground peers included, and the
laser path. Properties, each checked independently of viapath.guard:

* the only exception bad input may raise is the documented ObservationError;
* every command is finite and inside the motion limits;
* no command moves the robot towards an obstacle with a valid position that it could not stop
  short of (brute-force 1 ms roll-out in _helpers.moves_towards_close_obstacle).

Derandomized and bounded: 1 200 observations per planner (10 800 over the nine planners of a full
install) and 250 laser cycles; ``benchmarks/fuzz_entry.py`` runs the long version."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings

from tests.robustness._fuzz import observation_batches, scan_sets
from tests.robustness._helpers import fresh, inside_limits, moves_towards_close_obstacle
from viapath.observation import Observation, ObservationError, RobotState
from viapath.planning import available_planners

BATCH = 5
EXAMPLES_PER_PLANNER = 240  # x BATCH = 1 200 observations per planner
_PLANNERS: dict[str, object] = {}


def check_one(planner, observation) -> str | None:
    """None if the planner's answer to ``observation`` keeps every property, else what broke."""
    if isinstance(observation, ObservationError):
        return None  # refused while building it: the documented error
    try:
        decision = planner.plan(observation)
    except ObservationError:
        return None
    except Exception as error:
        return f"raised {type(error).__name__}: {error}"
    command = decision.command
    if not inside_limits(command, planner.limits):
        return f"command {command} not finite or outside the limits (status {decision.plan.status})"
    towards = moves_towards_close_obstacle(command, observation)
    if towards is not None:
        return (
            f"command {command} closes on obstacle {towards} within stopping distance (status {decision.plan.status})"
        )
    return None


@pytest.mark.parametrize("name", available_planners())
def test_fuzz_planner_entry(name):
    planner = _PLANNERS.setdefault(name, fresh(name))  # one planner, a stream of cycles: as on a robot

    @settings(
        max_examples=EXAMPLES_PER_PLANNER,
        deadline=None,
        derandomize=True,
        database=None,
        suppress_health_check=list(HealthCheck),
    )
    @given(observation_batches(BATCH))
    def run(batch):
        for observation in batch:
            problem = check_one(planner, observation)
            assert problem is None, (problem, observation)

    run()


def test_navground_peers_are_fuzzed_when_installed():
    pytest.importorskip("navground")
    assert {"nav-orca", "nav-hl", "nav-hrvo", "nav-sf"} <= set(available_planners())


def test_laser_path_never_turns_bad_scans_into_motion():
    from viapath.perception.laser import LaserPerception

    perception = LaserPerception()
    perception.reset(np.random.default_rng(0))
    counts = tuple(s.beam_count for s in perception.scanners)
    planner = fresh("viapath")
    clock = {"t": 0.0}

    @settings(max_examples=250, deadline=None, derandomize=True, database=None, suppress_health_check=list(HealthCheck))
    @given(scan_sets(counts))
    def run(scans):
        clock["t"] += 0.1
        pose = np.array([0.5 * np.sin(clock["t"]), 0.0, 0.1])
        try:
            obstacles = perception.process(clock["t"], pose, scans)
        except ObservationError:
            return
        assert np.isfinite(obstacles.positions).all() and np.isfinite(obstacles.velocities).all()
        observation = Observation(clock["t"], RobotState(pose[:2], pose[2], 0.2, 0.0, 0.25), obstacles)
        problem = check_one(planner, observation)
        assert problem is None, problem

    run()


@pytest.mark.parametrize(
    "scans, match",
    [
        ([np.full(683, 2.0)], r"scans: expected 2 scans, one per scanner \('front', 'rear'\)"),
        ([np.full(683, 2.0), np.full(600, 2.0)], r"scans\[1\] \(scanner 'rear'\): expected 683 ranges.*\(600,\)"),
        ([np.full((2, 683), 2.0), np.full(683, 2.0)], r"scans\[0\] \(scanner 'front'\)"),
    ],
)
def test_laser_path_names_the_bad_scan(scans, match):
    from viapath.perception.laser import LaserPerception

    perception = LaserPerception()
    if perception.scanners[0].beam_count != 683:
        pytest.skip("the default scanners changed")
    with pytest.raises(ObservationError, match=match):
        perception.process(0.0, np.zeros(3), scans)


def test_laser_scanner_without_a_message_is_all_invalid_not_an_error():
    from viapath.perception.laser import LaserPerception

    perception = LaserPerception()
    obstacles = perception.process(0.0, np.zeros(3), [None, np.full(perception.scanners[1].beam_count, np.nan)])
    assert len(obstacles) == 0


def test_the_long_fuzz_runs_the_hostile_input_and_construction_parts():
    """benchmarks/fuzz_entry.py's input and construction parts, a few cases each: no violation."""
    import importlib.util
    import sys
    from pathlib import Path

    script = Path(__file__).resolve().parents[2] / "benchmarks" / "fuzz_entry.py"
    spec = importlib.util.spec_from_file_location("fuzz_entry", script)
    fuzz = importlib.util.module_from_spec(spec)
    sys.path.insert(0, str(script.parents[1] / "tests" / "robustness"))
    try:
        spec.loader.exec_module(fuzz)
        inputs = fuzz.fuzz_inputs(15, 1)
        construction = fuzz.fuzz_construction(30, 1)
    finally:
        sys.path.remove(str(script.parents[1] / "tests" / "robustness"))
    for result in (inputs, construction):
        assert not any(key.startswith("VIOLATION") for key in result), result
    assert inputs["refused"] == 30 and construction["refused (OptionError)"] > 0
