"""Issue 12, findings 1-3: bad observation values never become motion; wrong shapes are refused.

Each test failed on main before the guarded entry (viapath.guard): there the obstacle with a bad
field vanished (every planner drove on at 0.2 m/s), NaN robot states gave NaN commands, and a
transposed obstacle array became a phantom obstacle at (0, 0)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.robustness._helpers import fresh, inside_limits, moves_towards_close_obstacle, one_obstacle, planners, robot
from viapath.observation import Observation, ObservationError, Obstacles
from viapath.scenarios import scenario_from_dict
from viapath.sim.loop import run_episode

BAD_FIELDS = {
    "velocity-nan": dict(velocity=(math.nan, 0.0)),
    "velocity-inf": dict(velocity=(math.inf, 0.0)),
    "radius-nan": dict(radius=math.nan),
    "radius-negative": dict(radius=-0.25),
    "sigma-nan": dict(velocity_sigma=math.nan),
}


@pytest.mark.parametrize("bad", sorted(BAD_FIELDS))
@pytest.mark.parametrize("name", [p for p in planners() if p != "follow"])  # follow ignores obstacles by design
def test_finding_1_obstacle_with_known_position_is_kept(name, bad):
    """Obstacle 0.6 m ahead (centre; 0.1 m surface gap) with one bad field: no planner drives into it."""
    observation = Observation(0.0, robot(speed=0.2), one_obstacle(**BAD_FIELDS[bad]))
    decision = fresh(name).plan(observation)
    free = fresh(name).plan(Observation(0.0, robot(speed=0.2), Obstacles.empty())).command
    assert inside_limits(decision.command)
    # What main commanded: the same as with no obstacle at all (0.2 m/s straight on). The obstacle
    # must change the command, and the command must not close in on it within stopping distance.
    assert decision.command != free, (name, bad, decision.command, decision.plan.status)
    assert decision.command.speed_mps < free.speed_mps - 0.05 or abs(decision.command.turn_rate_radps) > 0.3
    assert moves_towards_close_obstacle(decision.command, observation) is None, decision.command
    assert any("obstacles." in reason for reason in decision.plan.extras.get("guard", [])), decision.plan.extras


def _obstacle_in_closed_loop(**fields):
    return scenario_from_dict(
        {
            "name": "bad-field-ahead",
            "robot": {"start": [0.0, 0.0], "heading": 0.0, "speed": 0.2, "radius": 0.25},
            "path": {"waypoints": [[0.0, 0.0], [5.0, 0.0]], "half_width": 1.0},
            "obstacles": [{"start": [1.5, 0.0], "velocity": [0.0, 0.0], "radius": 0.25}],
            "duration_s": 6.0,
        }
    )


@pytest.mark.parametrize("bad", ["velocity-nan", "radius-nan", "sigma-nan"])
def test_finding_1_closed_loop_never_drives_through(bad, monkeypatch):
    """6 s closed loop with perception corrupting one field of the (standing) obstacle 1.5 m ahead:
    on main the robot drove through it (clearance -0.50 m)."""
    from viapath.sim import perception as perception_module

    original = perception_module.OraclePerception.observe

    def corrupted(self, world):
        seen = original(self, world)
        velocities, radii, sigma = seen.velocities.copy(), seen.radii_m.copy(), seen.velocity_sigma_mps.copy()
        if bad == "velocity-nan":
            velocities[:] = math.nan
        elif bad == "radius-nan":
            radii[:] = math.nan
        else:
            sigma[:] = math.nan
        return Obstacles(seen.positions, velocities, radii, seen.position_sigma_m, sigma, seen.ids)

    monkeypatch.setattr(perception_module.OraclePerception, "observe", corrupted)
    for name in ("viapath", "dwa", "vo", "stop"):
        episode = run_episode(_obstacle_in_closed_loop(), planner=name, perception="oracle")
        assert episode.metrics["min_clearance_m"] > 0.0, (name, bad, episode.metrics["min_clearance_m"])


NAN_STATES = {
    "position": dict(x=math.nan),
    "position-inf": dict(y=math.inf),
    "heading": dict(heading=math.nan),
    "speed": dict(speed=math.nan),
    "turn": dict(turn=math.inf),
}


@pytest.mark.parametrize("state", sorted(NAN_STATES))
@pytest.mark.parametrize("name", planners())
def test_finding_2_non_finite_robot_state_brakes(name, state):
    """A robot state that is not finite gives a stop (the hardest braking within the limits), and says why."""
    planner = fresh(name)
    decision = planner.plan(Observation(0.0, robot(**NAN_STATES[state]), one_obstacle(position=(3.0, 1.5))))
    assert decision.command.speed_mps == 0.0 and decision.command.turn_rate_radps == 0.0, decision.command
    assert decision.plan.status == "guard-stop"
    assert any(r.startswith("robot.") for r in decision.plan.extras["guard"]), decision.plan.extras


def test_finding_3_transposed_array_is_refused():
    positions = np.array([[1.0, 2.0, 3.0], [0.5, 0.5, 0.5]])  # (2, 3): three obstacles as columns
    with pytest.raises(ObservationError, match=r"obstacles\.positions: expected an \(N, 2\).*\(2, 3\)"):
        Obstacles(positions, np.zeros((2, 3)), np.full(3, 0.25))


@pytest.mark.parametrize(
    "fields, field",
    [
        (dict(positions=np.zeros((2, 2)), velocities=np.zeros((1, 2)), radii_m=np.full(2, 0.2)), "velocities"),
        (dict(positions=np.zeros((3, 2)), velocities=np.zeros((3, 2)), radii_m=np.full(2, 0.2)), "radii_m"),
        (
            dict(positions=np.zeros((3, 2)), velocities=np.zeros((3, 2)), radii_m=0.2, velocity_sigma_mps=np.zeros(4)),
            "velocity_sigma_mps",
        ),
        (dict(positions=np.zeros((3, 2)), velocities=np.zeros((3, 2)), radii_m=0.2, ids=[1, 2]), "ids"),
        (dict(positions=np.zeros(3), velocities=np.zeros(3), radii_m=0.2), "positions"),
    ],
)
def test_finding_3_mismatched_lengths_name_the_field(fields, field):
    with pytest.raises(ObservationError, match=rf"obstacles\.{field}: expected"):
        Obstacles(**fields)


def test_guard_brakes_motion_towards_a_close_obstacle():
    """follow ignores obstacles; the guard's last check still keeps it from closing in on one inside
    its stopping distance (checked with an independent roll-out)."""
    planner = fresh("follow")
    observation = Observation(0.0, robot(speed=0.2), one_obstacle(position=(0.52, 0.0)))
    decision = planner.plan(observation)
    assert moves_towards_close_obstacle(decision.command, observation) is None
    assert decision.plan.status == "guard-brake"
    # Far away, follow is untouched.
    far = Observation(0.0, robot(speed=0.2), one_obstacle(position=(3.0, 0.0)))
    assert fresh("follow").plan(far).command.speed_mps > 0.1
