"""Step 3, the costs: Eq. 1 as a sum of terms, each one compiled function scoring every candidate at once.

Source: paper §3 step 5, Eq. 1: ``E = k1·Dist + k2·Time + k3·|v − v_nominal| + k4·θ`` (Dist = length
through the via points to the subgoal in m, Time in s, θ = angle between the heading and the first
leg); the lowest E wins. The shape follows Nav2 MPPI's critics: each term is a small unit with a
weight, so new terms slot in without touching the search, and the plan can keep the breakdown.

Beyond the paper (docs/design.md §2 pitfalls):
* The speed term is time-weighted over a candidate that first slows down or waits, and each second it
  first stands still costs ``standing_cost`` more: Eq. 1 cannot tell standing for T from creeping at half
  the nominal speed for 2T (the same arrival, the same time-weighted speed error), and the paper slows
  down where both are free (its side-crossing case).
* :class:`SidePreference`: the head-on case ties left/right exactly and noise breaks it at random;
  the side other than ``preferred_side`` pays ``side_tolerance``.
* :class:`Hysteresis`: last cycle's way round (same obstacle, side, early/late) gets a bonus of
  ``hysteresis``, and half as much again at the same speed, so near-equal options do not alternate.
  It is negative cost, and the only term that depends on the previous cycle.

Each term is one compiled function (``*_term``): arrays with one entry per candidate in (the K leaves of the
candidate tree, as :class:`.candidates.Candidates` holds them), the weighted term of each candidate written
into ``out`` (K,) and returned. The compiled choice (:func:`.selection.choose_candidate`, which says why they are
inlined) calls the paper's six itself, in Eq. 1's order; a :class:`Critic` holds a term's name and weight (the plan's cost breakdown,
:func:`critics_for`) and its ``score`` calls the same function on a cycle's :class:`.candidates.Candidates`.
Critics after the paper's six are scored by their ``score`` between the choice's two compiled halves
(:func:`viapath.planning.viapath.choice.extra_critics`) and added after them, in their order. The terms share
this one module: each is a few lines, so Eq. 1 reads on one screen, and a new term goes after them
(docs/howto/add-cost-term.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from viapath.geometry import LEFT, RIGHT, angles_of
from viapath.jit import compiled
from viapath.options import Settings
from viapath.planning.viapath.candidates import Candidates, Choice, Way
from viapath.planning.viapath.rollout import wrap


@compiled(inline=True)
def distance_term(weight: float, length_m: np.ndarray, out: np.ndarray) -> np.ndarray:
    """k1·Dist: the length of each candidate through its via points to the subgoal."""
    for k in range(out.shape[0]):
        out[k] = weight * length_m[k]
    return out


@compiled(inline=True)
def time_term(weight: float, travel_s: np.ndarray, out: np.ndarray) -> np.ndarray:
    """k2·Time: how long each candidate takes to the subgoal, waiting included."""
    for k in range(out.shape[0]):
        out[k] = weight * travel_s[k]
    return out


@compiled(inline=True)
def speed_term(
    weight: float,
    standing_per_s: float,
    nominal_mps: float,
    speed_mps: np.ndarray,
    slow_s: np.ndarray,
    slow_speed_mps: np.ndarray,
    driven_s: np.ndarray,
    travel_s: np.ndarray,
    out: np.ndarray,
) -> np.ndarray:
    """k3·|v − v_nominal|, time-weighted over a first slow or waiting part (``slow_s`` at ``slow_speed_mps``, then
    ``driven_s`` at ``speed_mps``), plus ``standing_per_s`` for each second the candidate first stands still."""
    for k in range(out.shape[0]):
        slow_v = slow_speed_mps[k]
        error = (slow_s[k] * abs(slow_v - nominal_mps) + driven_s[k] * abs(speed_mps[k] - nominal_mps)) / travel_s[k]
        out[k] = weight * error + standing_per_s * (slow_s[k] if slow_v <= 0.0 else 0.0)
    return out


@compiled(inline=True)
def heading_term(
    weight: float, degrees: bool, heading_rad: float, first_angle_rad: np.ndarray, out: np.ndarray
) -> np.ndarray:
    """k4·θ: the turn from the robot's heading onto each candidate's first leg (radians, or degrees)."""
    for k in range(out.shape[0]):
        theta = abs(wrap(first_angle_rad[k] - heading_rad))  # type: ignore[no-untyped-call]  # rollout.py is unannotated
        out[k] = weight * (theta * (180.0 / math.pi) if degrees else theta)
    return out


@compiled(inline=True)
def side_term(weight: float, preferred: int, ways: np.ndarray, out: np.ndarray) -> np.ndarray:
    """Passing on the other side than ``preferred`` costs ``weight`` (``ways``: (K, 3) obstacle, side, root)."""
    for k in range(out.shape[0]):
        side = ways[k, 1]
        out[k] = weight * (1.0 if (side != 0 and side != preferred) else 0.0)
    return out


@compiled(inline=True)
def hysteresis_term(
    weight: float,
    has_previous: bool,
    obstacle: int,
    side: int,
    root: int,
    previous_mmps: int,
    ways: np.ndarray,
    speed_mps: np.ndarray,
    out: np.ndarray,
) -> np.ndarray:
    """Minus ``weight`` for last cycle's way round (``obstacle``, ``side``, ``root``), half as much again at its
    speed (``previous_mmps``, mm/s); 0 without a previous cycle."""
    if not has_previous:
        out[:] = 0.0
        return out
    for k in range(out.shape[0]):
        same_way = ways[k, 0] == obstacle and ways[k, 1] == side and ways[k, 2] == root
        same_speed = np.rint(speed_mps[k] * 1000) == previous_mmps
        bonus = (1.0 if same_way else 0.0) + 0.5 * (1.0 if (same_way and same_speed) else 0.0)
        out[k] = -(weight * bonus)
    return out


@dataclass(frozen=True)
class Context:
    """What the critics know of the cycle besides the candidates."""

    heading_rad: float
    nominal_speed_mps: float
    previous: Choice | None


class Critic:
    """One term of E: its ``name`` (its column in the plan's cost breakdown) and ``score``, the weighted term of
    every candidate of a cycle, (K,)."""

    name = ""

    def score(self, candidates: Candidates, context: Context) -> np.ndarray:  # pragma: no cover - interface
        raise NotImplementedError


@dataclass(frozen=True)
class Distance(Critic):
    """:func:`distance_term` as a critic."""

    weight: float
    name = "distance"

    def score(self, candidates: Candidates, context: Context) -> np.ndarray:
        return distance_term(self.weight, candidates.total_length_m, np.empty(len(candidates)))


@dataclass(frozen=True)
class Time(Critic):
    """:func:`time_term` as a critic."""

    weight: float
    name = "time"

    def score(self, candidates: Candidates, context: Context) -> np.ndarray:
        return time_term(self.weight, candidates.travel_time_s, np.empty(len(candidates)))


@dataclass(frozen=True)
class SpeedError(Critic):
    """:func:`speed_term` as a critic."""

    weight: float
    standing_per_s: float = 0.0
    name = "speed"

    def score(self, candidates: Candidates, context: Context) -> np.ndarray:
        c = candidates
        return speed_term(
            self.weight,
            self.standing_per_s,
            context.nominal_speed_mps,
            *(c.speed_mps, c.slow_s, c.slow_speed_mps, c.driven_s, c.travel_time_s),
            np.empty(len(c)),
        )


@dataclass(frozen=True)
class Heading(Critic):
    """:func:`heading_term` as a critic."""

    weight: float
    degrees: bool = False
    name = "heading"

    def score(self, candidates: Candidates, context: Context) -> np.ndarray:
        angles = angles_of(candidates.first_direction)
        return heading_term(self.weight, self.degrees, context.heading_rad, angles, np.empty(len(candidates)))


@dataclass(frozen=True)
class SidePreference(Critic):
    """:func:`side_term` as a critic."""

    weight: float
    preferred: int = LEFT
    name = "side"

    def score(self, candidates: Candidates, context: Context) -> np.ndarray:
        return side_term(self.weight, self.preferred, candidates.ways, np.empty(len(candidates)))


@dataclass(frozen=True)
class Hysteresis(Critic):
    """:func:`hysteresis_term` as a critic."""

    weight: float
    name = "hysteresis"

    def score(self, candidates: Candidates, context: Context) -> np.ndarray:
        previous = context.previous
        way, mmps = (previous.way, previous.speed_mmps) if previous is not None else (Way(0, 0, 0), 0)
        return hysteresis_term(
            self.weight,
            previous is not None,
            *(way.obstacle, way.side, way.root, mmps),
            candidates.ways,
            candidates.speed_mps,
            np.empty(len(candidates)),
        )


#: The critics whose terms the compiled choice sums itself, in this order (critics_for's); any after them are
#: scored with their own ``score`` (:func:`viapath.planning.viapath.choice.extra_critics`).
PAPER_CRITICS = (Distance, Time, SpeedError, Heading, SidePreference, Hysteresis)


def critics_for(config: Settings) -> tuple[Critic, ...]:
    """The critics of the viapath planner, from its options, in the order they are summed."""
    return (
        Distance(config.k1),
        Time(config.k2),
        SpeedError(config.k3, config.standing_cost),
        Heading(config.k4, degrees=config.theta_unit == "deg"),
        SidePreference(config.side_tolerance, LEFT if config.preferred_side == "left" else RIGHT),
        Hysteresis(config.hysteresis),
    )
