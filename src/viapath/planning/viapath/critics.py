"""Step 3, the costs: Eq. 1 as a sum of critics, each scoring every candidate at once.

Source: paper §3 step 5, Eq. 1: ``E = k1·Dist + k2·Time + k3·|v − v_nominal| + k4·θ`` (Dist = length
through the via points to the subgoal in m, Time in s, θ = angle between the heading and the first
leg); the lowest E wins. The shape follows Nav2 MPPI's critics: each term is a small object with a
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
  It is negative cost, and the only critic that depends on the previous cycle.

The critics are summed in the order listed in :func:`critics_for`, which is Eq. 1's order. The compiled choice
sums the paper's terms itself, each as its critic's ``score`` here says (:mod:`.selection`, held to these by
tests/planning/test_critics.py); critics after them are scored by their ``score`` between its two halves.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from viapath.geometry import LEFT, RIGHT, angles_of, wrap_angle
from viapath.options import Settings
from viapath.planning.viapath.candidates import Candidates, Choice


@dataclass(frozen=True)
class Context:
    """What the critics know of the cycle besides the candidates."""

    heading_rad: float
    nominal_speed_mps: float
    previous: Choice | None


class Critic:
    name = ""

    def score(self, candidates: Candidates, context: Context) -> np.ndarray:  # pragma: no cover - interface
        raise NotImplementedError


@dataclass(frozen=True)
class Distance(Critic):
    """k1·Dist: the length of the candidate through its via points to the subgoal."""

    weight: float
    name = "distance"

    def score(self, candidates: Candidates, context: Context) -> np.ndarray:
        return self.weight * candidates.total_length_m


@dataclass(frozen=True)
class Time(Critic):
    """k2·Time: how long the candidate takes to the subgoal, waiting included."""

    weight: float
    name = "time"

    def score(self, candidates: Candidates, context: Context) -> np.ndarray:
        return self.weight * candidates.travel_time_s


@dataclass(frozen=True)
class SpeedError(Critic):
    """k3·|v − v_nominal|, time-weighted over a first slow or waiting part, plus ``standing_per_s`` for
    each second the candidate first stands still."""

    weight: float
    standing_per_s: float = 0.0
    name = "speed"

    def score(self, candidates: Candidates, context: Context) -> np.ndarray:
        nominal = context.nominal_speed_mps
        driven_s = candidates.driven_s
        error = (
            candidates.slow_s * np.abs(candidates.slow_speed_mps - nominal)
            + driven_s * np.abs(candidates.speed_mps - nominal)
        ) / candidates.travel_time_s
        standing_s = np.where(candidates.slow_speed_mps <= 0.0, candidates.slow_s, 0.0)
        return self.weight * error + self.standing_per_s * standing_s


@dataclass(frozen=True)
class Heading(Critic):
    """k4·θ: the turn from the current heading onto the first leg (radians, or degrees by option)."""

    weight: float
    degrees: bool = False
    name = "heading"

    def score(self, candidates: Candidates, context: Context) -> np.ndarray:
        first = candidates.first_direction
        theta = np.abs(wrap_angle(angles_of(first) - context.heading_rad))
        return self.weight * (np.degrees(theta) if self.degrees else theta)


@dataclass(frozen=True)
class SidePreference(Critic):
    """Passing on the other side than ``preferred_side`` costs ``weight`` (breaks head-on ties)."""

    weight: float
    preferred: int = LEFT
    name = "side"

    def score(self, candidates: Candidates, context: Context) -> np.ndarray:
        side = candidates.ways[:, 1]
        return self.weight * ((side != 0) & (side != self.preferred))


@dataclass(frozen=True)
class Hysteresis(Critic):
    """Last cycle's way round earns ``weight``, its speed half as much again (negative cost)."""

    weight: float
    name = "hysteresis"

    def score(self, candidates: Candidates, context: Context) -> np.ndarray:
        previous = context.previous
        if previous is None:
            return np.zeros(len(candidates))
        same_way = previous.way.same(candidates.ways)
        same_speed = candidates.speed_mmps == previous.speed_mmps
        return -(self.weight * (same_way + 0.5 * (same_way & same_speed)))


#: The critics the compiled choice sums itself, in this order (critics_for's); any after them are scored with their
#: own ``score`` (:func:`viapath.planning.viapath.choice.extra_critics`).
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
