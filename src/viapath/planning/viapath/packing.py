"""The planner's calls of its compiled steps (:mod:`.legs`, :mod:`.via`, :mod:`.tree`, :mod:`.selection`,
:mod:`.rollout`, :mod:`.escape_figures`): each packs the cycle's arrays as
the compiled functions take them (C-contiguous float64, one value per obstacle) and reads what they hand back by
name (:class:`NodeStore`, :class:`CompiledChoice`). The settings go over as records, rows of :mod:`.records`'
dtypes, through small compiled doors (:func:`_choose` ...) that hand the steps the row's record.

A cycle runs its whole choice in one call (:func:`choose`), its escape in two (:func:`escape`); the recipe's
extensions (the way back, the outrun hold, the kept way, the closed way) call the leg checks on their own.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, NamedTuple

import numpy as np

from viapath.jit import compiled
from viapath.observation import MotionLimits
from viapath.planning.viapath import escape_figures as escape_steps
from viapath.planning.viapath import legs as leg_steps
from viapath.planning.viapath import records
from viapath.planning.viapath import rollout as rollout_steps
from viapath.planning.viapath import selection as selection_steps
from viapath.planning.viapath import tree as tree_steps
from viapath.planning.viapath import via as via_steps
from viapath.planning.viapath.shapes import StaticShapes

# The compiled steps take plain arrays and scalars unannotated (typed when they are compiled).
_legs: Any = leg_steps
_tree: Any = tree_steps
_via: Any = via_steps


# The doors of the steps that take a record: each takes the record's row (a plain argument, typed as fast as an array)
# where the step takes the record, and hands the step ``row[0]`` (:mod:`.records`). Their arguments are spelled out:
# with ``*arguments`` the compiler types them as one tuple, in Python, about 1.7 us a call more.
@compiled
def _choose(
    robot, speeds, subgoal, positions, velocities, radii, growth, until, via_radii, ids, shape_of, shape_members,
    shape_offsets, hug_factor, slow_radii, slow_growth, slow_until, slow_times, continuation, envelope, starts,
    directions, lengths, half_widths, waypoints, settings_row,
):  # fmt: skip
    """:func:`.selection.choose`; the static shapes come as their fields (a record argument from Python costs a call
    about 0.5 µs: the compiler types a tuple argument in Python)."""
    shapes = StaticShapes(shape_of, shape_members, shape_offsets, hug_factor)
    return selection_steps.choose(
        robot, speeds, subgoal, positions, velocities, radii, growth, until, via_radii, ids, shapes, slow_radii,
        slow_growth, slow_until, slow_times, continuation, envelope, starts, directions, lengths, half_widths,
        waypoints, settings_row[0],
    )  # fmt: skip


@compiled
def _choose_tree(
    robot, speeds, subgoal, obstacles, via, slow, continuation, envelope, corridor, waypoints, settings_row
):
    """:func:`.selection.choose_tree`, the settings' creep speed added to ``slow``."""
    settings = settings_row[0]
    slow_radii, slow_growth, slow_until, slow_times = slow
    slow = (slow_radii, slow_growth, slow_until, slow_times, settings.creep_speed_mps)
    return selection_steps.choose_tree(
        robot, speeds, subgoal, obstacles, via, slow, continuation, envelope, corridor, waypoints, settings
    )


@compiled
def _choose_ranked(robot, found, nf, ni, facts, extra, obstacles, corridor, settings_row):
    """:func:`.selection.choose_ranked`."""
    return selection_steps.choose_ranked(robot, found, nf, ni, facts, extra, obstacles, corridor, settings_row[0])


@compiled
def _can_follow(robot, target_x, target_y, angle, speed, settings_row, obstacles, corridor):
    """:func:`.rollout.can_follow` with the settings' roll-out steps."""
    settings = settings_row[0]
    return rollout_steps.can_follow(
        robot, target_x, target_y, angle, speed, settings, settings.rollout_steps, obstacles, corridor
    )


@compiled
def _escape_headings(robot, positions, velocities, radii, growth, until, row_turns, settings_row, steps):
    """:func:`.escape_figures.escape_headings`."""
    return escape_steps.escape_headings(
        robot, positions, velocities, radii, growth, until, row_turns, settings_row[0], steps
    )


@compiled
def _escape_scores(
    robot, commands, turn_rows, sines, cosines, positions, velocities, radii, growth, until, starts, directions,
    lengths, half_widths, subgoal, settings_row, steps, calm,
):  # fmt: skip
    """:func:`.escape_figures.escape_scores`."""
    return escape_steps.escape_scores(
        robot, commands, turn_rows, sines, cosines, positions, velocities, radii, growth, until, starts, directions,
        lengths, half_widths, subgoal, settings_row[0], steps, calm,
    )  # fmt: skip


class NodeStore(NamedTuple):
    """The candidate tree's node store of :func:`.tree.grow` / ``choose``, read by name
    (columns: :mod:`.records`)."""

    floats: np.ndarray  # (M, records.NODE_FLOATS)
    integers: np.ndarray  # (M, records.NODE_INTEGERS)

    def columns(self) -> dict[str, np.ndarray]:
        """The columns by name, as :class:`.candidates.Candidates` reads them (views, no copies)."""
        floats, integers = self.floats, self.integers
        return {
            "position": floats[:, records.N_X : records.N_Y + 1],
            "time_s": floats[:, records.N_TIME],
            "speed": floats[:, records.N_SPEED],
            "parent": integers[:, records.N_PARENT],
            "length_m": floats[:, records.N_LENGTH],
            "first_direction": floats[:, records.N_FIRST_X : records.N_FIRST_Y + 1],
            "way": integers[:, records.N_OBSTACLE : records.N_ROOT + 1],
            "slow_s": floats[:, records.N_SLOW_S],
            "slow_speed": floats[:, records.N_SLOW_SPEED],
        }

    def leaves(self) -> np.ndarray:
        """The nodes that end a complete candidate, in node order."""
        return np.flatnonzero(self.integers[:, records.N_LEAF])

    def to_goal_m(self, nodes) -> np.ndarray:
        """The length left from these nodes to the subgoal."""
        return self.floats[nodes, records.N_TO_GOAL]

    def ways(self, nodes) -> np.ndarray:
        """(len(nodes), 3) ways round: obstacle, side, root."""
        return self.integers[nodes, records.N_OBSTACLE : records.N_ROOT + 1]

    def way(self, node: int) -> list[int]:
        return self.integers[node, records.N_OBSTACLE : records.N_ROOT + 1].tolist()

    def position(self, node: int) -> np.ndarray:
        return self.floats[node, records.N_X : records.N_Y + 1]

    def parent(self, node: int) -> int:
        return int(self.integers[node, records.N_PARENT])

    def speed(self, node: int) -> float:
        return float(self.floats[node, records.N_SPEED])

    def slowing(self, node: int) -> tuple[float, float, float]:
        """The speed after the node's leg, its slow/wait time and the speed during it (0 s: no slowing)."""
        row = self.floats[node]
        return float(row[records.N_SPEED]), float(row[records.N_SLOW_S]), float(row[records.N_SLOW_SPEED])


class CompiledChoice(NamedTuple):
    """What :func:`.selection.choose` found, by name."""

    status: int  # records.NO_CANDIDATE, STEP_ONE or CANDIDATES
    turn_in_place: bool  # step 1 turns on the spot first
    leaves: np.ndarray  # (K,) the candidates' last nodes
    first: int  # the first rank whose candidate follows, -1: none tried follows
    order: list[int]  # candidates cheapest first (the ranks tried)
    follow: list[int]  # can_follow of each rank: 0 no, 1 yes, 2 after turning on the spot, -1 not tried
    total: np.ndarray  # (K,) E with only_way applied
    terms: np.ndarray  # (COST_TERMS + 1, K) each critic's term (critics_for's order), then their sum E
    store: NodeStore


def first_contacts(
    starts, start_times, velocities, checked, durations, packed_obstacles, leg_radii_m, shapes
) -> np.ndarray:
    """(K, N) first contact of each leg with each obstacle, inf = free (:func:`.legs.first_contacts`): people up to
    ``checked``, with ``leg_radii_m`` (None: none), static geometry over the whole ``durations``."""
    legs = np.zeros(len(starts)) if leg_radii_m is None else _c(leg_radii_m)
    return _legs.first_contacts(
        _c(starts), _c(start_times), _c(velocities), _c(checked), _c(durations), packed_obstacles, legs, shapes.shape_of
    )


def legs_inside(path, starts, ends, spacing_m: float, tolerance_m: float) -> np.ndarray:
    return _legs.legs_inside(
        *_corridor(path),
        _c(np.reshape(starts, (-1, 2))),
        _c(np.reshape(ends, (-1, 2))),
        float(spacing_m),
        float(tolerance_m),
    )


def goal_legs(checks, starts, start_times, speeds, horizon_s: float):
    """:meth:`.checks.LegChecks.goal_legs` in one compiled call."""
    obstacles = checks.packed_obstacles()
    return _legs.goal_legs(
        _c(starts),
        _c(start_times),
        _c(speeds),
        _c(checks.subgoal),
        float(checks.stop_short_m),
        float(horizon_s),
        checks.packed_continuation(),
        *obstacles,
        checks.packed_envelope(),
        *_corridor(checks.path),
        int(checks.subgoal_index),
        float(checks.corridor_check_spacing_m),
        float(checks.corridor_tolerance_m),
        checks.static_shapes().shape_of,
    )


def choose(
    checks,
    slow_checks,
    speeds,
    slow_times: np.ndarray,
    settings: np.ndarray,
    extra_terms: Callable[[NodeStore, np.ndarray], np.ndarray] | None = None,
):
    """The planner's choice up to its shield check in one compiled call (roots, step 1, the candidate tree,
    Eq. 1's critics, the order and the roll-outs up to the first candidate that follows):
    :func:`.selection.choose`, as a :class:`CompiledChoice`. ``slow_times`` (float64),
    ``settings`` the choice's (a row of :data:`.records.CHOICE`), filled in by the planner. With
    ``extra_terms`` (the terms (E, K) of critics after the paper's, of the tree's node store and its leaves) the
    choice takes two compiled calls, :func:`.selection.choose_tree` and :func:`.selection.choose_ranked`, and
    ``extra_terms`` between them; its terms join the choice's ``terms`` before their sum."""
    (
        robot,
        positions,
        velocities,
        radii,
        growth,
        until,
        via_radii,
        ids,
        continuation,
        envelope,
        starts,
        directions,
        lengths,
        half_widths,
        waypoints,
    ) = checks.packed_choice_inputs()
    _, _, slow_radii, slow_growth, slow_until = (
        (positions, velocities, radii, growth, until) if slow_checks is checks else slow_checks.packed_obstacles()
    )
    obstacles = (positions, velocities, radii, growth, until)
    shapes = checks.static_shapes()
    via = (via_radii, ids, shapes)
    slow = (slow_radii, slow_growth, slow_until, slow_times)
    corridor = (starts, directions, lengths, half_widths)
    if extra_terms is None:
        found, floats, integers, costs = _choose(
            robot, _c(speeds), _c(checks.subgoal), *obstacles, via_radii, ids, shapes.shape_of, shapes.members,
            shapes.offsets, shapes.hug_factor, *slow, continuation, envelope, *corridor, waypoints, settings,
        )  # fmt: skip
        return _choice_of(found, floats, integers, costs)
    inputs = (robot, _c(speeds), _c(checks.subgoal), obstacles, via, slow, continuation, envelope, corridor, waypoints)
    return _choose_in_halves(inputs, settings, extra_terms)


def _choose_in_halves(inputs, settings: np.ndarray, extra_terms) -> CompiledChoice:
    """:func:`choose` with ``extra_terms``: :func:`.selection.choose_tree`, the terms, :func:`.selection.choose_ranked`
    (the tree alone with :func:`TREE_ONLY`). ``inputs``: the robot, speeds, subgoal, obstacles, via, slow (without
    the creep speed), continuation, envelope, corridor and waypoints."""
    robot, speeds, subgoal, obstacles, via, slow, continuation, envelope, corridor, waypoints = inputs
    found, floats, integers_store, facts = _choose_tree(
        robot, speeds, subgoal, obstacles, via, slow, continuation, envelope, corridor, waypoints, settings
    )
    store = NodeStore(floats, integers_store)
    if extra_terms is TREE_ONLY:
        return CompiledChoice(int(found[0]), False, found[2:], -1, [], [], np.empty(0), np.empty((0, 0)), store)
    extra = _c(
        extra_terms(store, found[records.FOUND_LEAVES :]) if found[0] == records.CANDIDATES else np.empty((0, 0))
    )
    found, costs = _choose_ranked(robot, found, floats, integers_store, facts, extra, obstacles, corridor, settings)
    choice = _choice_of(found, floats, integers_store, costs)
    return choice._replace(
        terms=np.concatenate([choice.terms[: records.COST_TERMS], extra, choice.terms[records.COST_SUM :]])
    )


def TREE_ONLY(store: NodeStore, leaves: np.ndarray) -> np.ndarray:
    """:func:`choose`'s ``extra_terms`` for the candidate tree only (its status: whether it has candidates)."""
    raise AssertionError("a marker, never called")


def _escape_settings(checks, limits: MotionLimits, config, top: float, previous) -> np.ndarray:
    """The escape's settings row (:data:`.records.ESCAPE`); ``previous``: last cycle's command for a calm escape,
    else None."""
    dt = config.escape_dt_s
    calm = previous is not None
    return records.escape_settings(  # (by position, in the record's order: ESCAPE_FIELDS)
        dt,  # dt_s
        config.escape_s,  # escape_s
        limits.max_accel_mps2 * dt,  # speed_step_mps
        limits.max_turn_accel_radps2 * dt,  # turn_step_radps
        limits.max_speed_mps,
        limits.max_turn_rate_radps,
        checks.corridor_tolerance_m,
        max(config.escape_max_excess_m, checks.corridor_tolerance_m),  # max_excess_m
        max(top, 1e-9),  # top_speed_mps
        config.escape_continuity_s if calm else 0.0,  # continuity_s
        config.escape_progress_s,  # progress_s
        previous.speed_mps if calm else 0.0,  # previous_speed_mps
        previous.turn_rate_radps if calm else 0.0,  # previous_turn_radps
        checks.horizon_s,
        config.horizon_s,  # standing_check_s
    )


def escape(checks, limits: MotionLimits, config, fan, previous=None, score_standing: bool = False):
    """The escape's figures in two compiled calls: :func:`.escape_figures.escape_headings` (the standing
    check, the fan's headings), numpy's sines and cosines of those headings, :func:`.escape_figures.escape_scores`.
    Returns (standing is free, commands (K, 2), ends (K, 2), scores (K,)), the last three None when standing is
    free (unless ``score_standing``). ``fan``: :func:`.escape.escape_fan`'s (top speed, commands, distinct turn
    commands, each command's turn)."""
    top, commands, row_turns, turn_rows = fan
    steps = max(1, int(round(config.escape_s / config.escape_dt_s)))
    calm = bool(config.calm_escape and previous is not None)
    settings = _escape_settings(checks, limits, config, top, previous if calm else None)
    robot = checks.packed_robot()
    positions, velocities, radii, growth, until = checks.packed_obstacles()
    standing_free, headings = _escape_headings(
        robot, positions, velocities, radii, growth, until, row_turns, settings, steps
    )
    if standing_free and not score_standing:
        return True, None, None, None
    starts, directions, lengths, half_widths = _corridor(checks.path)
    ends, score = _escape_scores(
        robot,
        commands,
        turn_rows,
        np.sin(headings),
        np.cos(headings),
        positions,
        velocities,
        radii,
        growth,
        until,
        starts,
        directions,
        lengths,
        half_widths,
        _c(checks.subgoal),
        settings,
        steps,
        calm,
    )
    return standing_free, commands, ends, score


def can_follow(checks, target, speed_mps: float, limits: MotionLimits, config) -> int:
    """:func:`.rollout.can_follow` of steering for ``target`` at ``speed_mps`` from the robot of ``checks``: 0
    cannot, 1 can, 2 can after turning on the spot first."""
    settings = records.rollout_settings(_rollout_episode(limits, config), checks.corridor_tolerance_m)
    robot = checks.packed_robot()
    x, y = float(target[0]), float(target[1])
    angle = math.atan2(y - robot[1], x - robot[0])  # libm's, as the compiled choice takes it
    return int(
        _can_follow(robot, x, y, angle, float(speed_mps), settings, checks.packed_obstacles(), _corridor(checks.path))
    )


_rollout_cache: list[Any] = [None, None, b""]  # the last (limits, config) and their roll-out fields, packed


def _rollout_episode(limits: MotionLimits, config) -> bytes:
    """The roll-out's fields of the choice's settings (:func:`.records.choice_episode`, the others 0), packed once
    per (limits, config) object: :func:`can_follow` is called several times a cycle."""
    if _rollout_cache[0] is not limits or _rollout_cache[1] is not config:
        _rollout_cache[:] = (
            limits,
            config,
            records.choice_episode(zero_others=True, **records.rollout_fields(limits, config)),
        )
    return _rollout_cache[2]


def _choice_of(found, floats, integers, costs) -> CompiledChoice:
    """:class:`CompiledChoice` from choose's arrays: ``found`` (status, turn on the spot, the K leaves, then
    the ranking when there are candidates) and ``costs`` (records.COST_ROWS, K)."""
    store = NodeStore(floats, integers)
    status, turn = int(found[records.FOUND_STATUS]), bool(found[records.FOUND_TURN_IN_PLACE])
    if status != records.CANDIDATES:
        return CompiledChoice(
            status, turn, found[records.FOUND_LEAVES :], -1, [], [], costs[records.COST_TOTAL], costs, store
        )
    leaves_end = records.FOUND_LEAVES + costs.shape[1]
    leaves, ranking = found[records.FOUND_LEAVES : leaves_end], found[leaves_end:]
    ranks = int(ranking[records.RANKING_COUNT])
    order_end = records.RANKING_ORDER + ranks
    return CompiledChoice(
        status,
        turn,
        leaves,
        int(ranking[records.RANKING_FIRST]),
        ranking[records.RANKING_ORDER : order_end].tolist(),
        ranking[order_end:].tolist(),
        costs[records.COST_TOTAL],
        costs[: records.COST_SUM + 1],
        store,
    )


def _c(array) -> np.ndarray:
    return np.ascontiguousarray(array, dtype=np.float64)


def _corridor(path):
    """The path's segment arrays, C-contiguous float64 (cached on the path object)."""
    arrays = getattr(path, "_kernel_arrays", None)
    if arrays is None:
        arrays = (
            _c(path.segment_starts),
            _c(path.segment_directions),
            _c(path.segment_lengths_m),
            _c(path.half_widths_m),
        )
        path._kernel_arrays = arrays
    return arrays
