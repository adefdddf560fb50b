"""The guard's whole-array check of the obstacles (``guard._obstacles_sound``, the common case of every
cycle) decides exactly as its per-field checks: on observations with NaN, infinities, negative and
too large values sprinkled in, the inspection with the shortcut equals the one without it."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from viapath import guard
from viapath.guard_checks import Braking, braking_points
from viapath.observation import Observation, Obstacles, RobotState

_ODD = [np.nan, np.inf, -np.inf, -0.1, 0.0, 0.3, 0.6, 0.9, 1.2, 11.0, 2e6, -2e6]


@st.composite
def _observations(draw):
    n = draw(st.integers(0, 4))
    fields = {}
    for name, shape, base in (
        ("positions", (n, 2), 3.0),
        ("velocities", (n, 2), 1.0),
        ("radii", (n,), 0.3),
        ("position_sigma", (n,), 0.1),
        ("velocity_sigma", (n,), 0.1),
    ):
        values = np.full(shape, base) * np.array(
            draw(st.lists(st.floats(0.0, 1.0), min_size=int(np.prod(shape)), max_size=int(np.prod(shape))))
        ).reshape(shape)
        flat = values.reshape(-1)
        for index in draw(st.lists(st.integers(0, max(0, flat.size - 1)), max_size=2)) if flat.size else []:
            flat[index] = draw(st.sampled_from(_ODD))
        fields[name] = values
    obstacles = Obstacles(
        fields["positions"], fields["velocities"], fields["radii"], fields["position_sigma"], fields["velocity_sigma"]
    )
    speed = draw(st.sampled_from([0.2, 0.2, np.nan, 60.0]))
    return Observation(0.0, RobotState(np.zeros(2), 0.0, speed, 0.0, 0.25), obstacles)


@settings(max_examples=400, deadline=None, derandomize=True)
@given(_observations())
def test_shortcut_decides_as_the_per_field_checks(monkeypatch_observation):
    fast = guard.inspect_observation(monkeypatch_observation)
    original = guard._obstacles_sound
    guard._obstacles_sound = lambda *args: False  # every observation through the per-field checks
    try:
        slow = guard.inspect_observation(monkeypatch_observation)
    finally:
        guard._obstacles_sound = original
    assert fast.stop_reasons == slow.stop_reasons
    assert fast.repairs == slow.repairs
    assert (fast.observation is None) == (slow.observation is None)
    if fast.observation is not None and not fast.repairs:
        assert fast.observation is slow.observation  # nothing repaired: the observation itself, unchanged


def test_sound_obstacles_take_the_shortcut():
    obstacles = Obstacles(np.array([[1.0, 2.0]]), np.array([[0.3, 0.0]]), np.array([0.3]))
    assert guard._obstacles_sound(
        obstacles.positions,
        obstacles.velocities,
        obstacles.radii_m,
        obstacles.position_sigma_m,
        obstacles.velocity_sigma_mps,
        guard.DEFAULT_CONFIG,
    )
    for bad in (np.nan, np.inf, -1.0, 20.0):
        assert not guard._obstacles_sound(
            obstacles.positions,
            obstacles.velocities,
            np.array([bad]),
            obstacles.position_sigma_m,
            obstacles.velocity_sigma_mps,
            guard.DEFAULT_CONFIG,
        )


def test_a_planner_inside_a_guarded_one_is_not_inspected_again(monkeypatch):
    """The shield's planner gets the observation the shield's guard already inspected: it is not
    inspected a second time (same configuration), and the decisions (repairs reported included) are
    those of two inspections."""
    from viapath import DesignatedPath
    from viapath.planning import make_planner
    from viapath.safety.shielded import ShieldedPlanner

    path = DesignatedPath([[0.0, 0.0], [6.0, 0.0]], half_width_m=1.0)
    observations = [
        Observation(
            0.1 * k,
            RobotState(np.array([0.1 * k, 0.0]), 0.0, 0.2, 0.0, 0.25),
            Obstacles(
                np.array([[3.0, 0.1 * k], [2.0, 1.0]]),
                np.array([[-0.3, 0.0], [np.nan if k == 2 else 0.0, -0.2]]),
                np.array([0.3, 0.3]),
            ),
        )
        for k in range(4)
    ]  # cycle 2: a repair
    calls = []
    original = guard.inspect_observation
    monkeypatch.setattr(guard, "inspect_observation", lambda *a, **k: calls.append(1) or original(*a, **k))

    def decisions():
        planner = ShieldedPlanner(make_planner("viapath", path, nominal_speed_mps=0.2))
        return [planner.plan(o) for o in observations]

    once = decisions()
    assert len(calls) == len(observations)

    class NeverInspected:  # the marker switched off: every guarded plan inspects
        def get(self):
            return None

        def set(self, value):
            return None

        def reset(self, token):
            return None

    monkeypatch.setattr(guard, "_INSPECTED", NeverInspected())
    calls.clear()
    twice = decisions()
    assert len(calls) == 2 * len(observations)
    for a, b in zip(once, twice):
        assert a.command == b.command and a.plan.status == b.plan.status
        assert a.plan.extras.get("guard") == b.plan.extras.get("guard")
    assert any(d.plan.extras.get("guard") for d in once)  # the repair was there to compare


def braking_path(
    robot: RobotState,
    command,
    limits,
    period_s: float,
    samples_per_period: int = guard.BRAKING_SAMPLES_PER_PERIOD,
) -> np.ndarray:
    """The guard's braking roll-out (:func:`viapath.guard_checks.braking_points`) of the robot holding
    ``command`` for ``period_s`` and then commanded to stop until at rest: positions (S, 2), the current
    position excluded."""
    braking = Braking(
        float(limits.max_speed_mps),
        float(limits.max_turn_rate_radps),
        float(limits.max_accel_mps2),
        float(limits.max_turn_accel_radps2),
        float(period_s),
        int(samples_per_period),
    )
    return braking_points(
        float(robot.position[0]),
        float(robot.position[1]),
        float(robot.heading_rad),
        float(robot.speed_mps),
        float(robot.turn_rate_radps),
        float(command.speed_mps),
        float(command.turn_rate_radps),
        braking,
    )


def test_braking_path_steps_as_the_drive_model():
    """The guard's braking roll-out on plain floats gives kinematics.step's positions exactly: the held
    command (within the limits or not, not finite) for one period, then the stop until at rest."""
    from viapath.kinematics import UnicycleState, step
    from viapath.observation import Command, MotionLimits

    def reference(robot, command, limits, period_s, samples=5):
        dt = period_s / samples
        state = UnicycleState(
            float(robot.position[0]),
            float(robot.position[1]),
            float(robot.heading_rad),
            float(robot.speed_mps),
            float(robot.turn_rate_radps),
        )
        points = []
        for _ in range(samples):
            state = step(state, command, limits, dt)
            points.append((state.x, state.y))
        top = max(limits.max_speed_mps, abs(state.speed_mps))
        for _ in range(min(1000, int(np.ceil(top / max(limits.max_accel_mps2 * dt, 1e-9))) + 2)):
            if state.speed_mps <= 1e-12:
                break
            state = step(state, Command.stop(), limits, dt)
            points.append((state.x, state.y))
        return np.array(points)

    rng = np.random.default_rng(5)
    for trial in range(500):
        limits = MotionLimits(rng.uniform(0.3, 1.2), rng.uniform(0.3, 2.0), rng.uniform(0.5, 3.0), rng.uniform(1, 8))
        robot = RobotState(rng.uniform(-5, 5, 2), rng.uniform(-4, 4), rng.uniform(0.0, 1.5), rng.uniform(-3, 3), 0.25)
        v, w = rng.uniform(-0.2, 1.5), rng.uniform(-4, 4)
        if trial % 50 == 0:
            v = np.nan
        command = Command(v, w)
        np.testing.assert_array_equal(braking_path(robot, command, limits, 0.1), reference(robot, command, limits, 0.1))


@settings(max_examples=400, deadline=None, derandomize=True)
@given(
    _observations(),
    st.sampled_from(
        [
            guard.DEFAULT_CONFIG,
            guard.GuardConfig(max_velocity_sigma_mps=np.inf),
            guard.GuardConfig(max_coordinate_m=np.inf),
        ]
    ),
)
def test_an_inspected_observation_has_only_finite_obstacles(observation, config):
    """The planners' situation keeps every obstacle of an observation the guard has just inspected (or
    repaired) without looking again (``guard.inspected``): with finite bounds that is what
    ``Obstacles.finite`` would keep; with a bound at infinity it looks again."""
    from viapath import DesignatedPath
    from viapath.planning import make_planner

    seen = []
    planner = make_planner("viapath", DesignatedPath([[0.0, 0.0], [6.0, 0.0]], half_width_m=1.0))
    planner.guard_config = config
    original = planner.situation

    def situation(handed):
        found = original(handed)
        seen.append((guard.inspected(handed), handed.obstacles, found.obstacles))
        return found

    planner.situation = situation
    planner.plan(observation)
    for skipped, handed, kept in seen:
        finite = handed.finite()
        assert skipped == all(np.isfinite(float(getattr(config, name))) for name in config.__dataclass_fields__)
        for name in ("positions", "velocities", "radii_m", "position_sigma_m", "velocity_sigma_mps", "ids"):
            np.testing.assert_array_equal(getattr(kept, name), getattr(finite, name))


def test_the_shields_command_is_checked_once_when_it_is_the_planners(monkeypatch):
    """Behind the shield, both guards check the command; when the shield passes the planner's command on,
    the outer check is the inner one's answer, and every decision of an episode among people (guard
    brakes included) is the one of two separate checks."""
    from viapath.scenarios import load_scenario
    from viapath.sim.loop import run_episode

    scenario = load_scenario("paper-front")
    calls = []
    original = guard.check_command
    monkeypatch.setattr(guard, "check_command", lambda *a, **k: calls.append(a[0]) or original(*a, **k))
    once = run_episode(scenario, planner="viapath", perception="oracle", shield=True)
    checks_once = len(calls)
    monkeypatch.setattr(
        guard._GuardedCycle,
        "check",
        lambda self, command, limits, radius: original(command, self.observation, limits, radius, self.config),
    )
    twice = run_episode(scenario, planner="viapath", perception="oracle", shield=True)
    steps = len(twice.trace.commands) - 1
    assert checks_once < 1.5 * steps  # about one check per cycle, not two
    assert np.array_equal(once.trace.commands, twice.trace.commands)
    assert once.trace.plan_status == twice.trace.plan_status
    assert np.array_equal(once.trace.robot_poses, twice.trace.robot_poses)


def test_a_malformed_command_behind_the_shield_is_a_stop():
    """Behind the shield both guards check the command; a command whose fields are not floats (an array, a
    string) is never compared with the last one checked, it is checked: an array stops the robot, with the
    shield as without it (the comparison raised before this test), a number written as a string is read."""
    from viapath import DesignatedPath
    from viapath.observation import Command, Decision, Plan
    from viapath.planning.base import Planner
    from viapath.safety.shielded import ShieldedPlanner

    class Garbled(Planner):  # not registered: a planner whose command holds what a command must not
        def __init__(self, path, command):
            super().__init__(path)
            self.garbled = command

        def decide(self, situation):
            return Decision(self.garbled, Plan("straight", 0.2, situation.subgoal.copy()))

    path = DesignatedPath([[0.0, 0.0], [6.0, 0.0]], half_width_m=1.0)
    observation = Observation(
        0.0,
        RobotState(np.zeros(2), 0.0, 0.2, 0.0, 0.25),
        Obstacles(np.array([[3.0, 0.5]]), np.array([[-0.3, 0.0]]), np.array([0.3])),
    )
    for command in (Command(np.array([0.1, 0.2]), 0.0), Command(0.1, [0.0, 1.0])):
        for planner in (Garbled(path, command), ShieldedPlanner(Garbled(path, command))):
            decision = planner.plan(observation)
            assert decision.plan.status == "guard-stop", (command, type(planner).__name__)
            assert (decision.command.speed_mps, decision.command.turn_rate_radps) == (0.0, 0.0)
    # A number written as a string is read as the number (check_command's float()), behind the shield too.
    for planner in (Garbled(path, Command("0.1", 0.0)), ShieldedPlanner(Garbled(path, Command("0.1", 0.0)))):
        decision = planner.plan(observation)
        assert type(decision.command.speed_mps) is float and decision.command.speed_mps == 0.1
