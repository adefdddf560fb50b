"""The records of the planner's compiled steps, each field named once: the choice's settings (:data:`CHOICE`, read
as ``settings.k2_per_s`` by :func:`.selection.choose` and :func:`.rollout.can_follow`), the escape's
(:data:`ESCAPE`, :mod:`.escape_figures`), the columns of the candidate tree's node store (:mod:`.tree`) and the
entries of what the choice hands back. The rest of the planner builds the records here (:func:`choice_episode`,
:class:`ChoiceRow`, :func:`rollout_settings`, :func:`escape_settings`) and reads what comes back through
:mod:`.packing` (:class:`.packing.NodeStore`, :class:`.packing.CompiledChoice`), never by number.

Choices (measured on the development machine: a compiled call that reads four fields):

* A record is a numpy structured array of one row, its fields float64 or int64 (8 bytes each, no padding; flags are
  0/1 integers). The compiled steps take the row's record (``row[0]``, a reference into the row) and read a field at
  its fixed offset, as cheaply as an array item. the compiler types the row on each call about as fast as a plain array
  (one record: 0.5-0.7 µs a call, against 0.45-0.5 µs for the two flat arrays of slot numbers it replaces); a
  ``typing.NamedTuple`` reads as well inside but costs 6-7 µs a call to type (the compiler types a tuple argument in
  Python), and so does a numpy record scalar.
* :mod:`.packing` hands the rows to the compiled steps through small compiled doors that take ``row[0]``: inside,
  every step sees the record.
* The choice's row is kept per configuration (:class:`ChoiceRow`): the episode's fields packed once, the cycle's
  packed with :mod:`struct` into its bytes in place, 0.4 µs a cycle (a copy of the episode's bytes as a new row took
  1.2 µs, the flat arrays' copies and item sets about 1 µs; numpy sets one field of a structured array in about
  4 µs). The writers called every cycle take their fields by position, in the record's order (a call by keyword
  took about 2 µs more).
* The node store stays two 2-D arrays, floats and integers, with named columns (``N_X`` ...): the tree hands
  columns on as contiguous slices (node positions as (K, 2) rows) and the Python side reads them as views. A
  structured node store read faster in a compiled micro-benchmark (about half the time for a loop over 400 nodes'
  fields) but made each (K, 2) position array a copy, and rewrites every signature of the tree.
"""

from __future__ import annotations

import struct
from typing import Any

import numpy as np

_F, _I = "d", "q"  # struct's codes of float64 and int64 fields

# The choice's settings (CHOICE): first the episode's, constant while the options, motion limits and critics stay
# (:func:`choice_episode`) ...
CHOICE_EPISODE_FIELDS: tuple[tuple[str, str], ...] = (
    ("k1_per_m", _F),  # Eq. 1's weights: of the path length (per m), ...
    ("k2_per_s", _F),  # ... of the travel time (per s), ...
    ("k3_per_mps", _F),  # ... of the speed's error from the nominal speed (per m/s) ...
    ("k4_per_angle", _F),  # ... and of the first leg's turn (per degree or radian: heading_in_degrees)
    ("side_weight", _F),  # the cost of passing on the side not preferred
    ("hysteresis_weight", _F),  # the bonus of last cycle's way round (and speed)
    ("nominal_speed_mps", _F),
    ("rollout_heading_rad", _F),  # turns up to this (and small speed changes) are followed without a roll-out
    ("max_accel_mps2", _F),
    ("rollout_dt_s", _F),
    ("max_turn_rate_radps", _F),
    ("max_turn_accel_radps2", _F),
    ("max_speed_mps", _F),
    ("heading_gain", _F),  # the controller's turn rate per radian of heading error (1/s)
    ("turn_in_place_min_rad", _F),  # a roll-out that leaves the corridor may turn on the spot beyond this error
    ("corridor_check_spacing_m", _F),
    ("standing_per_s", _F),  # the cost of standing still per second
    ("creep_speed_mps", _F),  # the creep speed of slow/wait candidates (0: none)
    ("max_depth", _I),  # the candidate tree's depth
    ("max_root_obstacles", _I),  # the most obstacles a root leg branches on
    ("max_rollouts", _I),  # the most candidates rolled out, cheapest first
    ("rollout_steps", _I),  # a roll-out's steps of rollout_dt_s
    ("heading_in_degrees", _I),  # k4 prices the turn in degrees (1) or radians (0)
    ("preferred_side", _I),  # +1 left, -1 right, 0 none
    ("grows_slow", _I),  # whether slow/wait candidates are grown (slow times given)
)
# ... then the cycle's (:meth:`ChoiceRow.write`).
CHOICE_CYCLE_FIELDS: tuple[tuple[str, str], ...] = (
    ("stop_short_m", _F),  # how far short of a blocked subgoal legs end
    ("horizon_s", _F),
    ("corridor_tolerance_m", _F),  # how far outside the corridor a leg may go
    ("nominal_index", _I),  # the nominal speed's index in the speed set
    ("robot_segment", _I),  # the path segment the robot is on (0 when the subgoal index is below 2)
    ("subgoal_index", _I),
    ("try_step_one", _I),  # take the paper's step 1 (the straight leg) when it is free
    ("has_previous", _I),  # last cycle chose a candidate: its way round (obstacle, side, root) and speed (mm/s)
    ("previous_obstacle", _I),
    ("previous_side", _I),
    ("previous_root", _I),
    ("previous_speed_mmps", _I),
    ("only_one_way", _I),  # only one way round is allowed: obstacle, side, root
    ("only_obstacle", _I),
    ("only_side", _I),
    ("only_root", _I),
)

# The escape's settings (ESCAPE, :func:`.packing.escape`).
ESCAPE_FIELDS: tuple[tuple[str, str], ...] = (
    ("dt_s", _F),  # the roll-outs' step
    ("escape_s", _F),  # the roll-outs' length
    ("speed_step_mps", _F),  # the most the speed changes in one step
    ("turn_step_radps", _F),  # the most the turn rate changes in one step
    ("max_speed_mps", _F),
    ("max_turn_rate_radps", _F),
    ("corridor_tolerance_m", _F),
    ("max_excess_m", _F),  # a roll-out further outside the corridor than this is not taken (moving)
    ("top_speed_mps", _F),  # the fan's top speed (at least 1e-9)
    ("continuity_s", _F),  # a calm escape's weight of the change from last cycle's command (0: not calm)
    ("progress_s", _F),  # the weight of a free roll-out's progress towards the subgoal (per m/s)
    ("previous_speed_mps", _F),  # last cycle's command (calm escape)
    ("previous_turn_radps", _F),
    ("horizon_s", _F),  # the cycle's horizon ...
    ("standing_check_s", _F),  # ... and the options' one: standing is checked for the shorter
)


def _dtype(fields: tuple[tuple[str, str], ...]) -> np.dtype:
    """The structured dtype of ``fields``, its scalars numpy records (attribute access in plain Python, as compiled)."""
    base = np.dtype([(name, np.float64 if code == _F else np.int64) for name, code in fields], align=True)
    return np.dtype((np.record, base))


CHOICE = _dtype(CHOICE_EPISODE_FIELDS + CHOICE_CYCLE_FIELDS)
ESCAPE = _dtype(ESCAPE_FIELDS)
_EPISODE = struct.Struct("=" + "".join(code for _, code in CHOICE_EPISODE_FIELDS))
_CYCLE = struct.Struct("=" + "".join(code for _, code in CHOICE_CYCLE_FIELDS))
_ESCAPE = struct.Struct("=" + "".join(code for _, code in ESCAPE_FIELDS))
assert _EPISODE.size + _CYCLE.size == CHOICE.itemsize and _ESCAPE.size == ESCAPE.itemsize  # no padding
_FLOAT = struct.Struct("=d")
_TOLERANCE_AT = _EPISODE.size + 8 * [name for name, _ in CHOICE_CYCLE_FIELDS].index("corridor_tolerance_m")


def _packed(
    layout: struct.Struct, fields: tuple[tuple[str, str], ...], what: str, values: dict[str, float | int]
) -> bytes:
    names = [name for name, _ in fields]
    if set(values) != set(names):
        missing, unknown = sorted(set(names) - set(values)), sorted(set(values) - set(names))
        raise TypeError(f"{what}: missing fields {missing}, unknown fields {unknown}")
    return layout.pack(*(values[name] for name in names))


def choice_episode(zero_others: bool = False, **fields: float | int) -> bytes:
    """The episode's part of the choice's settings (every field of :data:`CHOICE_EPISODE_FIELDS`, by name, unless
    ``zero_others``: then the fields not given are 0), with the cycle's zero: what :class:`ChoiceRow` and
    :func:`rollout_settings` start from."""
    if zero_others:
        fields = {name: 0 for name, _ in CHOICE_EPISODE_FIELDS} | fields
    return _packed(_EPISODE, CHOICE_EPISODE_FIELDS, "the choice's settings", fields) + bytes(_CYCLE.size)


def rollout_fields(limits: Any, config: Any) -> dict[str, Any]:
    """The roll-out's fields of the choice's settings, of the motion limits and the planner's options (the follow
    check, :func:`.rollout.can_follow`, reads only these)."""
    return {
        "rollout_heading_rad": config.rollout_heading_rad,
        "max_accel_mps2": limits.max_accel_mps2,
        "rollout_dt_s": config.rollout_dt_s,
        "max_turn_rate_radps": limits.max_turn_rate_radps,
        "max_turn_accel_radps2": limits.max_turn_accel_radps2,
        "max_speed_mps": limits.max_speed_mps,
        "heading_gain": config.heading_gain,
        "turn_in_place_min_rad": config.turn_in_place_min_rad,
        "rollout_steps": max(1, int(round(config.rollout_s / config.rollout_dt_s))),
    }


class ChoiceRow:
    """The choice's settings for one configuration, a row of :data:`CHOICE` (:attr:`row`): the episode's fields
    packed once (:func:`choice_episode`), the cycle's (:data:`CHOICE_CYCLE_FIELDS`) written in place by
    :meth:`write` every cycle (0.4 µs; a fresh row each cycle took 1.2 µs). The row holds the fields last written:
    each compiled call takes it right after its :meth:`write`."""

    __slots__ = ("_buffer", "row")

    def __init__(self, episode: bytes):
        self._buffer = bytearray(episode)
        self.row = np.frombuffer(self._buffer, CHOICE)

    def write(
        self,
        stop_short_m: float,
        horizon_s: float,
        corridor_tolerance_m: float,
        nominal_index: int,
        robot_segment: int,
        subgoal_index: int,
        try_step_one: int,
        has_previous: int,
        previous_obstacle: int,
        previous_side: int,
        previous_root: int,
        previous_speed_mmps: int,
        only_one_way: int,
        only_obstacle: int,
        only_side: int,
        only_root: int,
    ) -> np.ndarray:
        """:attr:`row` with this cycle's fields (in the record's order: called every cycle, by position)."""
        _CYCLE.pack_into(
            self._buffer,
            _EPISODE.size,
            stop_short_m,
            horizon_s,
            corridor_tolerance_m,
            nominal_index,
            robot_segment,
            subgoal_index,
            try_step_one,
            has_previous,
            previous_obstacle,
            previous_side,
            previous_root,
            previous_speed_mmps,
            only_one_way,
            only_obstacle,
            only_side,
            only_root,
        )
        return self.row


def rollout_settings(episode: bytes, corridor_tolerance_m: float) -> np.ndarray:
    """The choice's settings for a roll-out on its own (:func:`.rollout.can_follow`), a row of :data:`CHOICE`: the
    episode's (:func:`choice_episode`) with the corridor tolerance, the cycle's other fields 0."""
    buffer = bytearray(episode)
    _FLOAT.pack_into(buffer, _TOLERANCE_AT, corridor_tolerance_m)
    return np.frombuffer(buffer, CHOICE)


def escape_settings(
    dt_s: float,
    escape_s: float,
    speed_step_mps: float,
    turn_step_radps: float,
    max_speed_mps: float,
    max_turn_rate_radps: float,
    corridor_tolerance_m: float,
    max_excess_m: float,
    top_speed_mps: float,
    continuity_s: float,
    progress_s: float,
    previous_speed_mps: float,
    previous_turn_radps: float,
    horizon_s: float,
    standing_check_s: float,
) -> np.ndarray:
    """The escape's settings, a row of :data:`ESCAPE` (its fields, :data:`ESCAPE_FIELDS`, in that order)."""
    return np.frombuffer(
        bytearray(
            _ESCAPE.pack(
                dt_s,
                escape_s,
                speed_step_mps,
                turn_step_radps,
                max_speed_mps,
                max_turn_rate_radps,
                corridor_tolerance_m,
                max_excess_m,
                top_speed_mps,
                continuity_s,
                progress_s,
                previous_speed_mps,
                previous_turn_radps,
                horizon_s,
                standing_check_s,
            )
        ),
        ESCAPE,
    )


# The node store of the candidate tree (grow, choose_tree): floats (M, NODE_FLOATS): position, time, speed,
# path length, first direction (unit x, y), slow/wait time and speed, length left to the subgoal; ...
N_X, N_Y, N_TIME, N_SPEED, N_LENGTH, N_FIRST_X, N_FIRST_Y, N_SLOW_S, N_SLOW_SPEED, N_TO_GOAL = range(10)
NODE_FLOATS = 10
# ... integers (M, NODE_INTEGERS): parent node (-1 for a root), way round (obstacle, side, root), leaf flag.
N_PARENT, N_OBSTACLE, N_SIDE, N_ROOT, N_LEAF = range(5)
NODE_INTEGERS = 5

# What choose_tree found (``found``): its status, whether step 1 turns on the spot, then the K leaves' nodes.
FOUND_STATUS, FOUND_TURN_IN_PLACE, FOUND_LEAVES = 0, 1, 2
NO_CANDIDATE, STEP_ONE, CANDIDATES = 0, 1, 2  # the status
# What choose_candidate ranks (``ranking``, after ``found`` in choose's first array): the first rank that
# follows (-1: none tried follows), R the ranks, then the order (R candidates) and each rank's can_follow (R).
RANKING_FIRST, RANKING_COUNT, RANKING_ORDER = 0, 1, 2
# Its costs (COST_ROWS, K): the six critics' terms (critics_for's order), their sum E, E with only_way applied.
COST_TERMS, COST_SUM, COST_TOTAL, COST_ROWS = 6, 6, 7, 8
