"""A robot hugging a static shape slides along it (candidates._with_slides): checked on a cycle that is
blocked without the slides, and against the slides' definition."""

from __future__ import annotations

import numpy as np
import pytest

from viapath import DesignatedPath, Observation, Obstacles, RobotState
from viapath.planning import make_planner
from viapath.planning.viapath import candidates
from viapath.planning.viapath import planner as viapath_planner
from viapath.static import StaticLayer, polygon_edges

# Two pillars (octagons, 0.2 m across the flats) near the path, as a generated static scene has them;
# the robot stands 0.22 m from the second one, west of it, turned away from the goal.
PILLARS = [
    [(3.0654, -0.0515), (3.006, 0.0918), (2.8628, 0.1511), (2.7195, 0.0918), (2.6601, -0.0515), (2.7195, -0.1948),
     (2.8628, -0.2542), (3.006, -0.1948)],
    [(4.2948, 0.5931), (4.2268, 0.7572), (4.0628, 0.8251), (3.8987, 0.7572), (3.8307, 0.5931), (3.8987, 0.429),
     (4.0628, 0.3611), (4.2268, 0.429)],
]  # fmt: skip


def _hugging_cycle(monkeypatch, hug_factor: float | None):
    if hug_factor is not None:
        monkeypatch.setattr(candidates, "HUG_FACTOR", hug_factor)
        # the tree's own verdict: without this, the flood's way round (blocked.detour) would find the way
        monkeypatch.setattr(viapath_planner, "detour", lambda *arguments: None)
    path = DesignatedPath([[0.0, 0.0], [6.8755, 0.0]], half_width_m=1.35)
    planner = make_planner("viapath", path, nominal_speed_mps=0.28)
    static = StaticLayer.of_shapes([polygon_edges(p) for p in PILLARS])
    robot = RobotState(np.array([3.3754, 0.5588]), -0.923, 0.0, 0.0, 0.25)
    return planner.plan(Observation(0.0, robot, Obstacles.empty(), static))


def test_a_robot_hugging_a_pillar_finds_a_way_round_it(monkeypatch):
    decision = _hugging_cycle(monkeypatch, None)
    assert decision.plan.status in ("avoid", "straight"), decision.plan.status
    assert decision.command.speed_mps > 0.0
    without = _hugging_cycle(monkeypatch, 0.0)
    assert without.plan.status == "blocked"  # the cycle this is about: tangents alone find no way round


def test_slides_are_one_via_radius_at_right_angles_to_the_disc():
    from viapath.planning.viapath.checks import LegChecks

    path = DesignatedPath([[0.0, 0.0], [6.0, 0.0]], half_width_m=1.5)
    planner = make_planner("viapath", path, nominal_speed_mps=0.3)
    static = StaticLayer.of_shapes([polygon_edges(PILLARS[0])])
    robot = RobotState(np.array([2.2, 0.0]), 0.0, 0.3, 0.0, 0.25)
    from viapath.guard import with_static_rows

    situation = planner.situation(with_static_rows(Observation(0.0, robot, Obstacles.empty(), static)))
    checks = LegChecks.of(situation, planner.config, planner.subgoals, planner.subgoal_policy, 0.25)
    obstacles = checks.obstacles
    rng = np.random.default_rng(3)
    index = rng.integers(0, len(obstacles), 6)
    # nodes at 0.8-1.4 via radii from their disc, in random directions
    bearing = rng.uniform(-np.pi, np.pi, 6)
    factor = np.array([0.8, 1.0, 1.2, 1.24, 1.3, 1.4])
    radii = checks.via_radii[index]
    starts = obstacles.positions[index] - (factor * radii)[:, None] * np.stack([np.cos(bearing), np.sin(bearing)], 1)
    speeds = np.full(6, 0.3)
    empty = (np.zeros(0, int), np.zeros(0, int), np.zeros(0), np.zeros((0, 2)), np.zeros((0, 2)))
    pair, option, t_k, velocity, via = candidates._with_slides(checks, starts, speeds, index, empty)
    expected_pairs = [k for k in range(6) if factor[k] < candidates.HUG_FACTOR]
    assert sorted(set(pair.tolist())) == expected_pairs
    for k, o, t, v, end in zip(pair, option, t_k, velocity, via):
        step = end - starts[k]
        toward = obstacles.positions[index[k]] - starts[k]
        assert np.hypot(*step) == pytest.approx(radii[k])
        assert abs(step @ toward) < 1e-9  # at right angles to the way to the disc
        side = np.sign(toward[0] * step[1] - toward[1] * step[0])  # +1: the slide is left of that way
        assert side == (1 if o == 0 else -1)
        assert np.allclose(v * t, step) and t == pytest.approx(radii[k] / 0.3)
