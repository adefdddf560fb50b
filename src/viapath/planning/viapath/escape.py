"""Step 6, no free candidate: stand if standing is safe, else escape.

Source: beyond the paper (it assumes some candidate is always free); DESIGN §2 and §7.

* If standing still is free over the horizon, the robot stops (status ``stop``).
* Otherwise even standing is hit. Of a fan of drive commands (arcs within the limits, and standing),
  each held for ``escape_s`` and rolled out with the drive's limits, take the best by, in order of
  importance: out of any overlap by the end and never deeper in on the way; no contact at all during
  the roll-out; never further out of the corridor than now (worth up to 2 s of time to contact: when
  stopping is not safe, not being hit comes first); the longest time to contact; then progress towards
  the subgoal, and slower rather than sideways (status ``escape``).
* Only people who could come within reach during the roll-out are scored (triangle inequality: the
  robot travels at most so far, each person |v|·T, each cone grows at most so much).
* When contact cannot be avoided, fleeing fast mostly runs into someone else: a contact at speed
  counts 0.5 s of time to contact per m/s against the command (a tie-break, no more: the longest time
  to contact still decides).
* A calm escape (``calm_escape``): never faster than the top of the speed set (the limits'
  top speed is for nothing the paper plans), and no flip from one cycle to the next: a command far
  from last cycle's escape command (speed change per top speed, turn change per turn-rate limit) pays
  up to ``escape_continuity_s`` seconds of time to contact. Before this, on ETH/UCY the speed command
  flipped between 0.6 and 0 m/s and the turn between -2 and +2 rad/s from one cycle to the next.
* An escape never takes the robot further than ``escape_max_excess_m`` outside the corridor (or
  further out than it already is): standing is always among the commands, and at rest the robot is
  passively safe (DESIGN §7); fleeing 10 m off the path is not.

:func:`escape_scores` is the reference. On the compiled path the planner hands :func:`stop_or_escape` the standing
check and the same scores, bit for bit, from two compiled calls (docs/CHANGELOG-speed.md, "The escape compiled");
it then decides from them as here.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any

import numpy as np

from viapath.kinematics import UnicycleState, rollout
from viapath.observation import Command, Decision, MotionLimits, Plan
from viapath.options import Settings
from viapath.planning.viapath.checks import LegChecks


def stop_or_escape(
    checks: LegChecks,
    limits: MotionLimits,
    config: Settings,
    previous: Command | None = None,
    compiled: tuple[Any, ...] | None = None,
) -> Decision:
    """``previous``: last cycle's command if last cycle escaped too (for a calm escape). ``compiled``: (standing is
    free, commands, ends, scores) from the planner's compiled path; None: worked out here."""
    position = checks.position
    base: dict[str, Any] = dict(subgoal_index=checks.subgoal_index)
    if compiled is None:
        standing = checks.contact_times(position[None], np.zeros(1), np.zeros((1, 2)), np.array([config.horizon_s]))
        standing_free = np.isinf(standing).all()
    else:
        standing_free, commands, ends, score = compiled
    if standing_free:
        return Decision(Command.stop(), Plan("stop", 0.0, position.copy(), **base))
    if compiled is None:
        commands, ends, score = escape_scores(checks, limits, config, previous)
    best = int(score.argmax())
    speed, turn = commands[best].tolist()
    return Decision(Command(speed, turn), Plan("escape", speed, ends[best], **base))


def escape_scores(
    checks: LegChecks, limits: MotionLimits, config: Settings, previous: Command | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Commands (v, ω), where each leaves the robot, and the score of each (higher is better)."""
    position = checks.position
    top, commands, row_turns, turn_rows = escape_fan(limits, config)
    dt = config.escape_dt_s
    steps = max(1, int(round(config.escape_s / dt)))
    state = UnicycleState(
        float(position[0]),
        float(position[1]),
        float(checks.heading_rad),
        float(checks.speed_mps),
        float(checks.turn_rate_radps),
    )
    positions = rollout(state, commands, limits, dt, steps, (row_turns, turn_rows))  # (K, S, 2)
    times = dt * np.arange(1, steps + 1)
    excess = checks.corridor_excess(positions.reshape(-1, 2)).reshape(len(commands), steps)
    inside = (excess <= checks.corridor_tolerance_m).all(axis=1)
    within_bound = excess.max(axis=1) <= max(config.escape_max_excess_m, checks.corridor_tolerance_m)

    horizon = steps * dt
    travel = float(np.hypot(*(positions - position).reshape(-1, 2).T).max())
    obstacles = checks.obstacles
    gap_all = np.hypot(*(position - obstacles.positions).T) - checks.check_radii
    growth_all = checks.growth * np.minimum(horizon, checks.growth_until_s)
    near = gap_all - growth_all - np.hypot(*obstacles.velocities.T) * horizon - travel <= 0
    # the people near: positions, velocities, check radii, cone growth and its cap
    radii, growth, until = checks.check_radii[near], checks.growth[near], checks.growth_until_s[near]
    people = (obstacles.positions[near], obstacles.velocities[near], radii, growth, until)
    gap_now = gap_all[near]
    overlapping = gap_now <= 0
    any_overlapping = bool(overlapping.any())
    compiled = checks.escape_contacts(positions, times, *people, overlapping, steps)
    if compiled is not None:  # the same figures, without the (K, S, N) arrays
        first_step, gap_min, gap_last = compiled
        time_to_contact = first_step * dt
    else:
        time_to_contact, gap_min, gap_last = _contacts(positions, times, *people, overlapping, steps, dt)
    if any_overlapping:
        deeper = gap_min - gap_now[overlapping]
        still_inside = gap_last
        separation = (np.minimum(deeper, 0.0) + np.minimum(still_inside, 0.0)).sum(axis=1)
    else:
        separation = np.zeros(len(commands))
    toward = checks.subgoal - position
    toward = toward / max(float(np.hypot(*toward)), 1e-9)
    # (end - position) · toward written out, the same sum on every machine (``@`` hands it to BLAS, whose routines
    # differ in whether they fuse the multiply and the add)
    ends = positions[:, -1]
    progress = ((ends[:, 0] - position[0]) * toward[0] + (ends[:, 1] - position[1]) * toward[1]) / config.escape_s
    free = time_to_contact >= steps * dt
    score = (
        1e2 * separation
        + 20.0 * free
        + 2.0 * inside
        + time_to_contact
        - np.where(free, 0.005, 0.5) * commands[:, 0]
        + 0.01 * progress
    )
    if config.calm_escape and previous is not None:
        change = (
            np.abs(commands[:, 0] - previous.speed_mps) / max(top, 1e-9)
            + np.abs(commands[:, 1] - previous.turn_rate_radps) / limits.max_turn_rate_radps
        )
        score = score - config.escape_continuity_s * np.minimum(change, 1.0)
    score = np.where(within_bound | (commands[:, 0] == 0.0), score, -np.inf)
    return commands, ends, score


def _contacts(
    positions: np.ndarray,
    times: np.ndarray,
    positions_obs: np.ndarray,
    velocities_obs: np.ndarray,
    check_radii: np.ndarray,
    growth: np.ndarray,
    growth_until_s: np.ndarray,
    overlapping: np.ndarray,
    steps: int,
    dt: float,
) -> tuple[np.ndarray, Any, Any]:
    """Of K roll-outs (positions (K, S, 2)) against the people near: the time to the first contact with anyone not
    overlapped now (K,), and the smallest and last gaps to those overlapped now ((K, M) each; None when none is)."""
    centres = positions_obs[None] + velocities_obs[None] * times[:, None, None]  # (S, N, 2)
    reach = check_radii + growth * np.minimum(times[:, None], growth_until_s)
    # The same differences as of the (K, S, N, 2) offsets, x and y apart and people first, (N, K, S):
    # every large operation below then runs contiguously along the steps.
    robot_x, robot_y = (np.ascontiguousarray(positions[..., axis]) for axis in (0, 1))  # (K, S)
    dx = robot_x[None] - np.ascontiguousarray(centres[..., 0].T)[:, None, :]  # (N, K, S)
    dy = robot_y[None] - np.ascontiguousarray(centres[..., 1].T)[:, None, :]
    reach = np.ascontiguousarray(reach.T)[:, None, :]  # (N, 1, S)
    any_overlapping = bool(overlapping.any())
    # The first step at which any person not overlapped now is touched (gap < 0): the earliest over
    # the people of each one's first step.
    touched: Any = touching(dx, dy, reach)
    if any_overlapping:  # (with no one overlapped, as mostly, the mask would change nothing)
        touched &= ~overlapping[:, None, None]
    touched = touched.any(axis=0)  # (K, S)
    time_to_contact = np.where(touched.any(axis=1), touched.argmax(axis=1), steps) * dt
    if not any_overlapping:
        return time_to_contact, None, None
    gap = np.hypot(dx[overlapping], dy[overlapping]) - reach[overlapping]  # (M, K, S)
    # (K, M) in C order, as the score sums them along M
    return time_to_contact, np.ascontiguousarray(np.min(gap, axis=2).T), np.ascontiguousarray(gap[:, :, -1].T)


def escape_top_speed(limits: MotionLimits, config: Settings) -> float:
    """The escape's top speed: the top of the speed set for a calm escape, else the limits' (m/s)."""
    return min(max(config.speeds), limits.max_speed_mps) if config.calm_escape else limits.max_speed_mps


def touching(dx: np.ndarray, dy: np.ndarray, reach_m: np.ndarray) -> np.ndarray:
    """``np.hypot(dx, dy) - reach_m < 0`` (broadcast), element for element, mostly without hypot: for the
    escape's (K, S, N) offsets hypot was its costliest step by far. The squared distance (three cheap
    operations) is within a few 1e-16 of the square of hypot's result, so outside a band of ±1e-9 (relative)
    around the reach the answer is certain; inside it, and wherever a square could underflow or a reach
    is not positive (or NaN), hypot itself decides (tests/planning/test_numpy_shortcuts.py tries the band)."""
    reach_m = np.asarray(reach_m, dtype=float)
    below = np.square(reach_m * (1.0 - 1e-9))
    below = np.where((reach_m > 0) & (below > 1e-280), below, 0.0)  # closer than this: touching
    above = np.maximum(np.square(reach_m * (1.0 + 1e-9)), 1e-280)  # further than this: not (NaN: never)
    squared = dx * dx + dy * dy
    result = squared < below
    unsure = ~(result | (squared > above))
    if unsure.any():
        shape = np.broadcast_shapes(np.shape(dx), np.shape(dy), reach_m.shape)
        pick: Callable[[Any], np.ndarray] = lambda values: np.broadcast_to(values, shape)[unsure]
        result[unsure] = np.hypot(pick(dx), pick(dy)) - pick(reach_m) < 0
    return result


@functools.lru_cache(maxsize=64)
def _fan(speeds: tuple[float, ...], top: float, max_turn_rate_radps: float) -> np.ndarray:
    """The escape's commands (v, ω): standing, the speed set up to ``top`` and ``top``, each with 9 turn
    rates across the limits. The same every cycle of a planner, so made once (read-only)."""
    speed_grid = np.unique(np.concatenate([[0.0], np.minimum(speeds, top), [top]]))
    turns = np.linspace(-max_turn_rate_radps, max_turn_rate_radps, 9)
    commands = np.stack([grid.ravel() for grid in np.meshgrid(speed_grid, turns)], axis=1)
    commands.flags.writeable = False
    return commands


def escape_fan(limits: MotionLimits, config: Settings) -> tuple[Any, ...]:
    """The top speed, the fan's commands (K, 2), its distinct turn commands (T,) and each command's index
    among them (K,), for :func:`escape_scores`' roll-out and the compiled escape (given them by the planner: the compiled
    package does not import this module, which imports the checks, which import the compiled package), which take the headings, sines and cosines once per turn command: the commands of one turn
    rate share them."""
    return _fan_turns(tuple(config.speeds), escape_top_speed(limits, config), limits.max_turn_rate_radps)


@functools.lru_cache(maxsize=64)
def _fan_turns(speeds: tuple[float, ...], top: float, max_turn_rate_radps: float) -> tuple[Any, ...]:
    commands = _fan(speeds, top, max_turn_rate_radps)
    row_turns, turn_rows = np.unique(commands[:, 1], return_inverse=True)
    turn_rows = turn_rows.astype(np.int64).reshape(-1)
    for array in (row_turns, turn_rows):
        array.flags.writeable = False
    return top, commands, row_turns, turn_rows
