"""Step 2, the candidates: for every speed of the set, the ways to the subgoal in x-y-t, as the candidate tree
(:mod:`.tree`, compiled) grows them; here what the rest of the planner reads of them.

Source: paper §3 steps 1-3 (after Tsubouchi et al.'s iterated forecast and planning); docs/design.md §2.

Every candidate is a chain of legs at one constant speed, grown as a tree of (position, time)
nodes. **The speed loop is the roots**: one root node per speed of the set (plus the current and the
nominal speed), all at the robot, at t = 0. From each node the straight leg to the subgoal is tried:

* a free straight leg completes a candidate ("speed up to stay ahead", "slow down and let it
  pass" are straight candidates at other speeds);
* a blocked one branches to the **via points** of the obstacle it hits (avoiding line ∩ reachable
  cone, :func:`viapath.geometry.via_times`): both sides and, when the obstacle is faster, both roots
  (pass early / let it overtake). At the root we branch on every obstacle the straight leg hits
  (earliest first, at most ``max_root_obstacles``), deeper only on the first one hit. Depth is
  bounded by ``max_depth``; a via leg that meets an obstacle or leaves the corridor drops its branch.

Beyond the paper (docs/design.md §2 and §5.2 future work):
* **Slow / wait**: stand still, creep (``creep_speed_mps``, below the speed set) or drive at a speed of
  the set slower than nominal along the straight leg for each of ``slow_times_s``, then on at the
  nominal speed, or at the slowest faster speed whose leg is free when the nominal one's is not. Once
  the way is clear the robot drives the straight leg at the nominal speed (step 1), so a faster
  continuation would be a plan it never drives, and would make waiting look quicker than slowing
  down. Letting a crossing person pass is then a straight candidate, not a sharp turn behind them. The leg after waiting is checked to its end, not
  to the horizon: waiting is for letting someone pass, not for pushing a collision past the horizon.
  The slow leg itself is checked with ``slow_leg_inflation`` of the uncertainty inflation: at a tenth
  of a metre per second the robot stops within millimetres, the next cycles correct the forecast, and
  the shield (docs/design.md §7) keeps it passively safe; with the full cone a freshly tracked crossing person
  made the robot wait where the paper slows down (laser paper-side).
* **Corners**: when the straight leg to the subgoal would cut a corner of the corridor (the robot
  was pushed back, or a blocked subgoal was given up), the path's own corners between the robot and
  the subgoal become via points: the way back along the designated path.
* **Static geometry** (docs/design.md §10): a static disc met by a leg stands for its whole shape
  (:mod:`.shapes`: one branch per shape at the root, via points round the shape's extreme discs, slides
  along a shape the node hugs).

Each candidate records its **way round** — the first obstacle it avoids, the side and the root
(:class:`Way`) — so that the next cycle can prefer the same way (hysteresis) without comparing
positions.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

# The "obstacle" of a way that is not round an obstacle.
STRAIGHT = -1  # the straight leg to the subgoal (or a chain grown from it)
SLOW = -2  # first slows down or waits
CORNER = -3  # back along the path through a corner (the corner's index as the way's 'root')


@dataclass(frozen=True)
class Way:
    """Which way round a candidate goes: (first obstacle id or STRAIGHT/SLOW/CORNER, side, root)."""

    obstacle: int
    side: int
    root: int

    def same(self, ways: np.ndarray) -> np.ndarray:
        """Which rows of a (K, 3) way array go this way round (at any speed)."""
        return np.all(ways == (self.obstacle, self.side, self.root), axis=1)


@dataclass
class Choice:
    """What the planner chose last cycle: the way round and the speed (mm/s)."""

    way: Way
    speed_mmps: int


@dataclass
class Candidates:
    """The complete candidates of one cycle, as arrays (one row each): what the critics score."""

    nodes: dict[str, np.ndarray]  # the whole tree, stacked
    leaves: np.ndarray  # the node each candidate ends in (before its last, straight leg)
    total_length_m: np.ndarray
    speed_mps: np.ndarray  # the speed of the candidate's driven legs
    slow_s: np.ndarray  # how long it first slows down or waits (0: never)
    slow_speed_mps: np.ndarray
    first_direction: np.ndarray  # (K, 2) unit vector of the first leg
    ways: np.ndarray  # (K, 3) obstacle, side, root
    subgoal: np.ndarray

    def __len__(self) -> int:
        return len(self.leaves)

    @property
    def driven_s(self) -> np.ndarray:
        return (self.total_length_m - self.slow_speed_mps * self.slow_s) / self.speed_mps

    @property
    def travel_time_s(self) -> np.ndarray:
        return self.slow_s + self.driven_s

    @property
    def speed_mmps(self) -> np.ndarray:
        return np.round(self.speed_mps * 1000).astype(int)


def candidates_of(store: Any, subgoal: np.ndarray) -> Candidates:
    """The candidates of the candidate tree's node store (:class:`.packing.NodeStore`), leaves in node order."""
    data = store.columns()
    leaves = store.leaves()
    return Candidates(
        nodes=data,
        leaves=leaves,
        total_length_m=data["length_m"][leaves] + store.to_goal_m(leaves),
        speed_mps=data["speed"][leaves],
        slow_s=data["slow_s"][leaves],
        slow_speed_mps=data["slow_speed"][leaves],
        first_direction=data["first_direction"][leaves],
        ways=data["way"][leaves],
        subgoal=subgoal,
    )
