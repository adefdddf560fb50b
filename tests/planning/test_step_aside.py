"""Stepping aside (``step_aside_s``, :mod:`viapath.planning.viapath.step_aside`), closed loop, oracle perception.

The robot waits in front of a closed door (status ``blocked``, at x = 0.9 m; the wall is at x = 1.5 m) when a
person who does not react to it walks straight at it from the side at 0.6 m/s. In a wide corridor it steps
out of their way and keeps clear; in a corridor too narrow to let them pass, it stays, and every command it
sends is one the shield admits. The step's safety claim, that the move keeps clear of the forecast over the
whole roll-out, is checked by an independent brute force: the robot driven by the control law the module
states, integrated finely, against the person's forecast disc.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from viapath.observation import MotionLimits
from viapath.scenarios import load_scenario
from viapath.sim.loop import run_episode
from viapath.sim.metrics import clearance_per_step

OFF = {"step_aside_s": 0.0}

_DOOR = """
name: {name}
description: a robot waiting at a closed door, a person walking straight at it
robot: {{start: [0.0, 0.0], heading: 0.0, speed: 0.2, radius: 0.25}}
path:
  waypoints: [[0.0, 0.0], [6.0, 0.0]]
  half_width: {half_width}
walls:
  - {{points: [[1.5, -2.0], [1.5, 2.0]], until_s: 30.0}}
obstacles:
  - {{start: {start}, velocity: {velocity}, radius: 0.25, start_time_s: 10.0}}
duration_s: 60
"""


def _scenario(tmp_path, name: str, half_width: float, start, velocity):
    file = tmp_path / f"{name}.yaml"
    file.write_text(_DOOR.format(name=name, half_width=half_width, start=list(start), velocity=list(velocity)))
    return load_scenario(file)


def _run(scenario, overrides=None, on_step=None):
    return run_episode(
        scenario,
        perception="oracle",
        seed=0,
        position_noise_m=0.0,
        velocity_noise_mps=0.0,
        planner_overrides=overrides,
        on_step=on_step,
    )


@pytest.fixture(scope="module")
def wide(tmp_path_factory):
    """Corridor ±1.5 m; the person comes down x = 1.15 (where the robot waits) from y = 3 m."""
    scenario = _scenario(tmp_path_factory.mktemp("wide"), "wide", 1.5, [1.15, 3.0], [0.0, -0.6])
    records = []
    stepping = _run(scenario, on_step=records.append)
    return scenario, stepping, records, _run(scenario, OFF)


def test_in_a_wide_corridor_the_waiting_robot_steps_out_of_the_persons_way(wide):
    _, stepping, _, staying = wide
    trace, metrics = stepping.trace, stepping.metrics
    status = np.array(trace.plan_status)
    assert (status == "step-aside").sum() >= 3
    assert metrics["reached_goal"] and not metrics["collision"]
    assert metrics["time_outside_corridor_s"] == 0.0
    assert np.abs(trace.robot_poses[:, 1]).max() <= 1.5
    # It keeps more room from the person than without the step (these two runs: 0.29 m against 0.08 m,
    # surface to surface), at least step_aside_clearance_m (0.2 m).
    person_gap = clearance_per_step(trace).min()
    assert person_gap >= 0.2
    assert person_gap >= clearance_per_step(staying.trace).min() + 0.1
    # Out of the way before the person arrives: when the person crosses the robot's waiting line (y = 0) the
    # robot is at least a combined radius plus 0.2 m away.
    k = int(np.argmax(trace.obstacle_positions[:, 0, 1] <= 0.0))
    gap = np.hypot(*(trace.robot_poses[k, :2] - trace.obstacle_positions[k, 0]))
    assert gap >= 0.5 + 0.2


def test_with_no_room_to_step_aside_the_robot_stays_and_sends_only_admitted_commands(tmp_path):
    """Corridor ±0.3 m (the robot's centre may move 0.3 m sideways, the person needs 0.55 m to pass), the door
    ahead, the person walking up the path from behind: no move lets them pass. The robot only backs off
    towards the door as far as the static world lets it (never towards the person), sends only commands the
    shield admits, and the person walks into a robot at rest; the same contact as without the step."""
    scenario = _scenario(tmp_path, "narrow", 0.3, [-4.0, 0.0], [0.6, 0.0])
    records = []
    stepping = _run(scenario, on_step=records.append)
    staying = _run(scenario, OFF)
    trace, metrics = stepping.trace, stepping.metrics
    for episode in (stepping, staying):
        assert episode.metrics["collision"] and not episode.metrics["at_fault_collision"]
    assert metrics["time_outside_corridor_s"] == 0.0 and metrics["static_contact"] == 0
    contact = int(np.argmax(clearance_per_step(trace) < 0.0))
    assert trace.robot_speeds_mps[contact] == 0.0
    assert np.abs(trace.robot_poses[:, 1]).max() <= 0.3 + 1e-9
    for record in records[:contact]:
        # Every command sent before the contact is one the shield admits (never one into a predicted collision).
        sent = np.array([trace.commands[record.step]])
        assert record.planner.shield.evaluate(record.observation, sent)["admissible"][0], record.time_s
        if record.decision.plan.status == "step-aside":  # away from the person, towards the door
            person = record.world.obstacle_positions[0]
            here = record.observation.robot.position
            assert np.hypot(*(record.decision.plan.target - person)) > np.hypot(*(here - person))
            assert record.decision.plan.target[0] <= 1.5 - 0.25


def _brute_force_gap(state, target, cap_mps, person, radius_m, horizon_s, limits: MotionLimits) -> float:
    """The smallest gap, over ``horizon_s``, between the robot steering for ``target`` and the person's forecast
    disc (centre p + v t, radius ``radius_m``): the module's stated control law (turn towards the target at
    2.5/s of heading error, full speed within 45° of it and none from 90°, no faster than ``cap_mps`` nor than
    it can stop from within what is left beyond 0.02 m), commanded every 0.1 s, speed and turn rate ramped at
    the limits at the start of each period, and integrated here with 1 ms Euler steps."""
    x, y, heading, speed, turn = state
    position, velocity = np.asarray(person[0], float), np.asarray(person[1], float)
    smallest = math.inf
    fine = 1e-3
    for period in range(int(round(horizon_s / 0.1))):
        dx, dy = target[0] - x, target[1] - y
        distance = math.hypot(dx, dy)
        allowed = 0.0 if distance <= 0.02 else min(cap_mps, math.sqrt(2 * limits.max_accel_mps2 * (distance - 0.02)))
        error = math.remainder(math.atan2(dy, dx) - heading, 2 * math.pi)
        w_cmd = max(-limits.max_turn_rate_radps, min(limits.max_turn_rate_radps, 2.5 * error))
        v_cmd = allowed * max(0.0, min(1.0, (math.pi / 2 - abs(error)) / (math.pi / 4)))
        if allowed <= 0.0:
            v_cmd = w_cmd = 0.0
        speed += max(-limits.max_accel_mps2 * 0.1, min(limits.max_accel_mps2 * 0.1, v_cmd - speed))
        turn += max(-limits.max_turn_accel_radps2 * 0.1, min(limits.max_turn_accel_radps2 * 0.1, w_cmd - turn))
        for i in range(100):
            t = period * 0.1 + i * fine
            centre = position + velocity * t
            smallest = min(smallest, math.hypot(x - centre[0], y - centre[1]) - radius_m)
            x += speed * math.cos(heading) * fine
            y += speed * math.sin(heading) * fine
            heading += turn * fine
    return smallest


def test_every_step_aside_keeps_clear_of_the_forecast_by_brute_force(wide):
    """Each cycle that stepped aside: the move it commanded, driven on to its target as the module states,
    keeps the robot outside the person's forecast disc (robot + person radius + safety margin) over the
    whole ``step_aside_s``."""
    _, _, records, _ = wide
    limits = MotionLimits()
    horizon_s = 3.0  # the option's default
    margin = 0.05  # safety_margin_m's default; oracle perception: no uncertainty inflation
    cycles = [r for r in records if r.decision.plan.status == "step-aside"]
    assert cycles
    for record in cycles:
        robot = record.observation.robot
        people = record.observation.obstacles
        person = [i for i in range(len(people)) if people.static_mask is None or not people.static_mask[i]]
        assert len(person) == 1
        plan = record.decision.plan
        # The plan's speed is the cap the command was made with; the law caps at the top of the speed set.
        state = (*robot.position, robot.heading_rad, robot.speed_mps, robot.turn_rate_radps)
        gap = _brute_force_gap(
            state,
            plan.target,
            0.5,
            (people.positions[person[0]], people.velocities[person[0]]),
            0.25 + float(people.radii_m[person[0]]) + margin,
            horizon_s,
            limits,
        )
        assert gap >= -1e-3, (record.time_s, gap)
        assert plan.extras["step_aside"]["clearance_m"] <= gap + 0.02
