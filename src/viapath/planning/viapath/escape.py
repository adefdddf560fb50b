"""Step 6, no free candidate: stand if standing is safe, else escape.

Source: beyond the paper (it assumes some candidate is always free); docs/design.md §2 and §7.

* If standing still is free over the horizon, the robot stops (status ``stop``).
* Otherwise even standing is hit. Of a fan of drive commands (arcs within the limits, and standing),
  each held for ``escape_s`` and rolled out with the drive's limits, take the best by, in order of
  importance: out of any overlap by the end and never deeper in on the way; no contact at all during
  the roll-out; never further out of the corridor than now (worth up to 2 s of time to contact: when
  stopping is not safe, not being hit comes first); the longest time to contact; then progress towards
  the subgoal, and slower rather than sideways (status ``escape``).
* Among the commands that stay clear over the whole roll-out (they tie on time to contact), progress towards
  the subgoal is worth ``escape_progress_s`` seconds of time to contact per m/s. By default (0.01) it is a
  tie-break and the calm escape's continuity keeps last cycle's command: in ETH/UCY crowds those escapes drove
  on at about 0.2 m/s and got nowhere along the path, and most of the time lost in the windows where the robot
  missed its goal was lost there (benchmarks/reach_failures.py). With a weight above the continuity (5) the
  robot escapes onwards and reaches its goal more often, but it also drives on towards people coming at it
  whom it must then flee (a group abreast filling the corridor then meets it moving, not at rest), so it is
  not the default. A command that is not clear keeps progress as a tie-break: there the time to contact
  decides.
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
  passively safe (docs/design.md §7); fleeing 10 m off the path is not.

The standing check and the fan's scores are compiled (:func:`viapath.planning.viapath.packing.escape`, two calls); the
choice among them is made here.
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from viapath.observation import Command, Decision, MotionLimits, Plan
from viapath.options import Settings
from viapath.planning.viapath import packing
from viapath.planning.viapath.checks import LegChecks


def stop_or_escape(
    checks: LegChecks, limits: MotionLimits, config: Settings, previous: Command | None = None
) -> Decision:
    """Stop if standing is free over the horizon, else the best-scored drive command of the fan.
    ``previous``: last cycle's command if last cycle escaped too (for a calm escape)."""
    position = checks.position
    base: dict[str, Any] = dict(subgoal_index=checks.subgoal_index)
    standing_free, commands, ends, score = packing.escape(checks, limits, config, escape_fan(limits, config), previous)
    if standing_free:
        return Decision(Command.stop(), Plan("stop", 0.0, position.copy(), **base))
    best = int(score.argmax())
    speed, turn = commands[best].tolist()
    return Decision(Command(speed, turn), Plan("escape", speed, ends[best], **base))


def escape_top_speed(limits: MotionLimits, config: Settings) -> float:
    """The escape's top speed: the top of the speed set for a calm escape, else the limits' (m/s)."""
    return min(max(config.speeds), limits.max_speed_mps) if config.calm_escape else limits.max_speed_mps


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
    among them (K,), for the compiled escape, which takes the headings, sines and cosines once per turn command:
    the commands of one turn rate share them. Kept for the last (limits, options) objects: asked every escape."""
    last = _last_fan[0]  # (one read: planners in other threads may replace it)
    if last is None or last[0] is not limits or last[1] is not config:
        fan = _fan_turns(tuple(config.speeds), escape_top_speed(limits, config), limits.max_turn_rate_radps)
        last = _last_fan[0] = (limits, config, fan)
    return last[2]


_last_fan: list[Any] = [None]  # escape_fan's last (limits, options, fan)


@functools.lru_cache(maxsize=64)
def _fan_turns(speeds: tuple[float, ...], top: float, max_turn_rate_radps: float) -> tuple[Any, ...]:
    commands = _fan(speeds, top, max_turn_rate_radps)
    row_turns, turn_rows = np.unique(commands[:, 1], return_inverse=True)
    turn_rows = turn_rows.astype(np.int64).reshape(-1)
    for array in (row_turns, turn_rows):
        array.flags.writeable = False
    return top, commands, row_turns, turn_rows
