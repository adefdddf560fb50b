"""The compiled shield (numba, extra ``fast``) gives the numpy reference's verdicts (issue 16, DESIGN §7).

Random single cycles (hypothesis, derandomized): robot state and motion limits, control period,
shield options (both modes, ``towards_only`` both), 0-30 people with positions (some touching the
robot, some far beyond reach), velocities and uncertainties, and commands inside and outside the
dynamic window (some not finite). For each, the two backends' ``Shield.evaluate`` must give the
same admissible / friendly / person / contact arrays and meet times equal to 1e-9, and
``Shield.filter`` the same command (1e-9), ``intervened``, ``reason`` and counts.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from viapath.compiled import ENVIRONMENT_VARIABLE, numba_available
from viapath.observation import Command, MotionLimits, Observation, Obstacles, RobotState
from viapath.safety import Shield, ShieldConfig

pytestmark = pytest.mark.skipif(not numba_available(), reason="numba (extra 'fast') is not installed")

MAX_PEOPLE = 30


def make_case(rng: np.random.Generator, n: int, mode: str, towards_only: bool, far: float, uncertain: bool, k: int):
    """One random cycle: limits, control period, shield options, observation, K commands."""
    vmax, amax = rng.uniform(0.2, 1.2), rng.uniform(0.3, 2.0)
    wmax, alphamax = rng.uniform(0.5, 3.0), rng.uniform(1.0, 10.0)
    limits = MotionLimits(vmax, amax, wmax, alphamax)
    dt = float(rng.choice([0.05, 0.1, 0.2]))
    config = ShieldConfig(
        mode=mode,
        towards_only=towards_only,
        margin_m=rng.uniform(0.0, 0.2),
        person_accel_mps2=rng.uniform(0.0, 2.0) * float(rng.choice([0.0, 1.0, 1.0])),
        sigma_multiplier=rng.uniform(0.0, 3.0),
        samples=int(rng.integers(3, 12)),
        substep_s=float(rng.choice([0.01, 0.025, 0.05, 0.2])),
    )
    position = rng.uniform(-5, 5, 2)
    speed = vmax * float(rng.choice([0.0, 1.0, 1.0])) * rng.uniform(0, 1)
    robot = RobotState(
        position,
        rng.uniform(-np.pi, np.pi),
        speed,
        wmax * rng.uniform(-1, 1) * float(rng.choice([0, 1])),
        rng.uniform(0.15, 0.4),
    )
    # People mostly within a few metres (a few touching the robot, a share ``far`` beyond any reach),
    # half walking at it, some standing.
    distance = np.where(rng.uniform(size=n) < far, rng.uniform(5.0, 30.0, n), rng.uniform(0.2, 4.0, n))
    bearing = rng.uniform(-np.pi, np.pi, n)
    positions = position + np.stack([distance * np.cos(bearing), distance * np.sin(bearing)], 1)
    walking = rng.uniform(0.0, 2.0, n) * rng.choice([0.0, 1.0, 1.0, 1.0], n)
    direction = np.where(
        rng.uniform(size=n) < 0.5, bearing + np.pi + rng.normal(0, 0.4, n), rng.uniform(-np.pi, np.pi, n)
    )
    velocities = np.stack([walking * np.cos(direction), walking * np.sin(direction)], 1)
    people = Obstacles(
        positions,
        velocities,
        rng.uniform(0.1, 0.35, n),
        rng.uniform(0.0, 0.1, n) if uncertain else None,
        rng.uniform(0.0, 0.3, n) if uncertain else None,
    )
    # Commands: inside and outside the window, the extreme corner, and a few not finite.
    commands = np.stack([rng.uniform(-0.3, 1.5, k) * vmax, rng.uniform(-1.5, 1.5, k) * wmax], 1)
    commands[rng.uniform(size=k) < 0.1] = [vmax, wmax]
    commands[rng.uniform(size=k) < 0.05] = [np.nan, 0.0]
    commands[rng.uniform(size=k) < 0.05] = [np.inf, -np.inf]
    return limits, dt, config, Observation(0.0, robot, people), commands


@st.composite
def cases(draw):
    rng = np.random.default_rng(draw(st.integers(0, 2**31 - 1)))
    return make_case(
        rng,
        draw(st.integers(0, MAX_PEOPLE)),
        draw(st.sampled_from(["passive", "passive-friendly"])),
        draw(st.booleans()),
        draw(st.sampled_from([0.0, 0.2, 1.0])),
        draw(st.booleans()),
        draw(st.integers(1, 30)),
    )


def _shields(limits, dt, config):
    numpy_shield = Shield(limits, dt, ShieldConfig(**{**config.__dict__, "compute": "numpy"}))
    numba_shield = Shield(limits, dt, ShieldConfig(**{**config.__dict__, "compute": "numba"}))
    assert (numpy_shield.backend, numba_shield.backend) == ("numpy", "numba")
    return numpy_shield, numba_shield


@settings(max_examples=1000, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck))
@given(cases())
def test_numba_shield_gives_the_numpy_verdicts(case):
    limits, dt, config, observation, commands = case
    numpy_shield, numba_shield = _shields(limits, dt, config)
    expected = numpy_shield.evaluate(observation, commands)
    found = numba_shield.evaluate(observation, commands)
    for key in ("admissible", "friendly", "person", "contact"):
        np.testing.assert_array_equal(found[key], expected[key], err_msg=key)
    np.testing.assert_allclose(found["meet_time_s"], expected["meet_time_s"], rtol=0, atol=1e-9)
    np.testing.assert_array_equal(found["achieved"], expected["achieved"])
    for command in commands[:1]:
        a = numpy_shield.filter(observation, Command(*command))
        b = numba_shield.filter(observation, Command(*command))
        assert (b.command.speed_mps, b.command.turn_rate_radps) == pytest.approx(
            (a.command.speed_mps, a.command.turn_rate_radps), abs=1e-9
        )
        assert (b.intervened, b.reason, b.admissible, b.friendly, b.person_id) == (
            a.intervened,
            a.reason,
            a.admissible,
            a.friendly,
            a.person_id,
        )
        assert (b.candidates, b.admissible_candidates) == (a.candidates, a.admissible_candidates)
        assert (a.meet_time_s is None) == (b.meet_time_s is None)
        if a.meet_time_s is not None:
            assert math.isclose(a.meet_time_s, b.meet_time_s, abs_tol=1e-9)
        assert (a.backend, b.backend) == ("numpy", "numba")


def test_the_cases_reach_every_branch():
    """The random cases are not trivial: contacts, meetings, all clear, unfriendly commands, searches."""
    rng = np.random.default_rng(0)
    seen = {"contact": 0, "met": 0, "clear": 0, "unfriendly": 0, "replaced": 0, "none admissible": 0}
    for i in range(300):
        mode = ("passive", "passive-friendly")[i % 2]
        limits, dt, config, observation, commands = make_case(
            rng,
            int(rng.integers(0, MAX_PEOPLE + 1)),
            mode,
            bool(i % 3),
            float(rng.choice([0.0, 0.2, 1.0])),
            bool(i % 5),
            int(rng.integers(1, 31)),
        )
        shield = Shield(limits, dt, ShieldConfig(**{**config.__dict__, "compute": "numba"}))
        verdict = shield.evaluate(observation, commands)
        contact = bool(verdict["contact"][0])
        seen["contact"] += contact
        seen["met"] += int(not contact and np.isfinite(verdict["meet_time_s"]).any())
        seen["clear"] += int(len(observation.obstacles) > 0 and verdict["admissible"].all())
        seen["unfriendly"] += int(np.any(verdict["admissible"] & ~verdict["friendly"]))
        result = shield.filter(observation, Command(*commands[0]))
        seen["replaced"] += int(result.intervened and result.admissible)
        seen["none admissible"] += int(not contact and not result.admissible)
    assert min(seen.values()) >= 5, seen


def test_backend_option_and_environment(monkeypatch):
    monkeypatch.setenv(ENVIRONMENT_VARIABLE, "numpy")
    assert Shield(config=ShieldConfig()).backend == "numpy"  # the environment overrides auto
    assert Shield(config=ShieldConfig(compute="numba")).backend == "numba"  # not an explicit choice
    monkeypatch.setenv(ENVIRONMENT_VARIABLE, "numba")
    assert Shield(config=ShieldConfig()).backend == "numba"
    with pytest.raises(ValueError, match="compute"):
        ShieldConfig(compute="fortran")


def test_auto_waits_for_the_compiled_shield_and_precompile_builds_it(monkeypatch):
    """A plain ``auto`` does not make a short run wait ~12 s for numba: before the kernels are compiled
    (in this process or numba's disk cache) it runs the numpy reference; ``precompile`` (what
    ``viapath bench`` and the ROS 2 node call first) builds them, and an explicit choice compiles too."""
    from viapath.compiled import ready
    from viapath.compiled import shield as kernels
    from viapath.safety import shield as shield_module
    from viapath.safety.shield import precompile

    monkeypatch.delenv(ENVIRONMENT_VARIABLE, raising=False)
    monkeypatch.setattr(shield_module, "ready", lambda *kernels: False)
    assert Shield().backend == "numpy"
    assert Shield(config=ShieldConfig(compute="numba")).backend == "numba"
    monkeypatch.setenv(ENVIRONMENT_VARIABLE, "numba")
    assert Shield().backend == "numba"
    monkeypatch.undo()
    monkeypatch.delenv(ENVIRONMENT_VARIABLE, raising=False)
    assert precompile() is True
    assert ready(kernels.shield)  # in this process or in numba's disk cache
    assert Shield().backend == "numba"
