"""The way back to the path after an avoidance (option ``return_lookahead_m``, beyond the paper;
docs/howto/tune-weights.md §6): off the path line the planner first tries the straight leg at the nominal speed
to the path point ``return_lookahead_m`` ahead, instead of the shallow line to a far subgoal."""

from __future__ import annotations

import numpy as np
import pytest

from viapath.observation import Obstacles
from viapath.path import DesignatedPath
from viapath.planning.viapath.checks import LegChecks
from viapath.scenarios import load_scenario
from viapath.sim.loop import run_episode


def _checks(position, subgoal_index=1) -> LegChecks:
    path = DesignatedPath([[0.0, 0.0], [8.0, 0.0], [8.0, 4.0]], half_width_m=1.0)
    return LegChecks(
        path=path,
        position=np.asarray(position, float),
        heading_rad=0.0,
        speed_mps=0.25,
        turn_rate_radps=0.0,
        subgoal=path.waypoints[subgoal_index],
        subgoal_index=subgoal_index,
        is_final_subgoal=False,
        obstacles=Obstacles.empty(),
        check_radii=np.zeros(0),
        growth=np.zeros(0),
        growth_until_s=np.zeros(0),
        via_radii=np.zeros(0),
        horizon_s=10.0,
        stop_short_m=0.0,
        continuation=(path.segment_directions[subgoal_index], path.segment_lengths_m[subgoal_index]),
        corridor_tolerance_m=0.0,
        corridor_check_spacing_m=0.05,
    )


def test_the_way_back_aims_at_the_path_point_ahead_and_checks_on_to_the_subgoal():
    back = _checks([3.0, 0.6]).back_to_path(1.0)
    np.testing.assert_allclose(back.subgoal, [4.0, 0.0])
    direction, length = back.continuation
    np.testing.assert_allclose(direction, [1.0, 0.0])
    assert length == pytest.approx(4.0)  # from the point on to the subgoal at x = 8
    assert back.stop_short_m == 0.0


def test_no_way_back_on_the_path_line_or_within_the_lookahead_of_the_subgoal():
    assert _checks([3.0, 0.005]).back_to_path(1.0) is None  # on the line: the leg to the subgoal is the way back
    assert _checks([7.2, 0.6]).back_to_path(1.0) is None  # the point would lie past the subgoal


@pytest.fixture(scope="module")
def overtaking():
    """The built-in overtaking scenario (k2 = 0.01: it passes the slow walker), as the paper does it
    and with the way back."""
    scenario = load_scenario("overtaking")
    return {
        lookahead: run_episode(
            scenario,
            perception="oracle",
            seed=0,
            position_noise_m=0.0,
            velocity_noise_mps=0.0,
            planner_overrides={"return_lookahead_m": lookahead},
        )
        for lookahead in (0.0, 1.0)
    }


def _back_on_the_line_x(trace, walker_passed_x_m: float, within_m: float = 0.05) -> float:
    """Where the robot, once ahead of the walker, is first back within ``within_m`` of the path line."""
    poses = trace.robot_poses
    ahead = poses[:, 0] > trace.obstacle_positions[:, 0, 0] + walker_passed_x_m
    on_line = ahead & (np.abs(trace.path.lateral_deviation(poses[:, :2])) < within_m)
    return float(poses[np.argmax(on_line), 0]) if on_line.any() else np.inf


def test_with_the_way_back_the_robot_is_back_on_the_path_soon_after_the_pass(overtaking):
    paper, back = overtaking[0.0], overtaking[1.0]
    for episode in (paper, back):
        assert episode.metrics["reached_goal"] and not episode.metrics["collision"]
    # The paper's way drifts back towards the goal 8 m away; the way back is on the line metres sooner.
    assert _back_on_the_line_x(back.trace, 0.5) < _back_on_the_line_x(paper.trace, 0.5) - 2.0
    assert back.metrics["mean_lateral_deviation_m"] < 0.75 * paper.metrics["mean_lateral_deviation_m"]
    # ... at almost no cost in time.
    assert back.metrics["time_to_goal_s"] <= paper.metrics["time_to_goal_s"] + 1.0
    assert back.metrics["time_outside_corridor_s"] == 0


def test_the_way_back_is_on_by_default_and_changes_nothing_on_the_path(overtaking):
    from viapath.planning.viapath.options import VIAPATH_OPTIONS
    from viapath.presets import preset_values

    # The default is the measured best (docs/howto/tune-weights.md §7); the paper's planner has none.
    assert VIAPATH_OPTIONS.defaults()["return_lookahead_m"] == 0.5
    assert preset_values("paper")["return_lookahead_m"] == 0.0
    # Before the pass the robot is on the line: both runs are the same up to there.
    paper, back = overtaking[0.0].trace, overtaking[1.0].trace
    first_off = int(np.argmax(np.abs(paper.path.lateral_deviation(paper.robot_poses[:, :2])) > 0.01))
    np.testing.assert_array_equal(paper.robot_poses[: first_off + 1], back.robot_poses[: first_off + 1])
