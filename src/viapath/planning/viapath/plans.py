"""A chosen candidate as the planner hands it on: the way round and speed it remembers for the next cycle, the
plan, and the cycle's candidates (for the kept way); the straight leg's plan (paper step 1), and the cost terms of
Eq. 1 that a plan reports.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from viapath.observation import Command, MotionLimits
from viapath.options import Settings
from viapath.path import DesignatedPath, SubgoalTracker
from viapath.planning.base import Plan, Situation
from viapath.planning.viapath.candidates import STRAIGHT, Candidates, Choice, Way, _candidates_of
from viapath.planning.viapath.checks import LegChecks
from viapath.planning.viapath.critics import Critic
from viapath.planning.viapath.packing import NodeStore


class CompiledCandidates:
    """The compiled choice's candidates: their ways round at once (what :meth:`ViaPathPlanner._keep_previous_way`
    reads), everything else of :class:`Candidates` built from the node store when first asked for."""

    _built: Candidates | None

    def __init__(self, store: NodeStore, leaves: np.ndarray, subgoal: np.ndarray):
        self._store, self._leaves, self._subgoal, self._built = store, leaves, subgoal, None

    @property
    def ways(self) -> np.ndarray:
        return self._store.ways(self._leaves)

    def __getattr__(self, name: str) -> Any:
        if name.startswith("_"):
            raise AttributeError(name)
        if self._built is None:
            self._built = _candidates_of(self._store, self._subgoal)
        return getattr(self._built, name)

    def __len__(self) -> int:
        return len(self._leaves)


@dataclass
class Chosen:
    choice: Choice
    plan: Plan
    # None for the paper's step 1 (a free straight leg at nominal speed)
    candidates: Candidates | CompiledCandidates | None


class Planning(Protocol):
    """What the recipe's named steps (:mod:`.choice`, :mod:`.way_back`, :mod:`.outrun`, :mod:`.kept_way`,
    :mod:`.blocked`) use of the planner (:class:`.planner.ViaPathPlanner`): its settings, its memory of the
    last cycles, and the recipe's own steps they call back."""

    config: Settings
    settings: Settings
    limits: MotionLimits
    critics: tuple[Critic, ...]
    nominal_speed_mps: float
    robot_radius_m: float
    path: DesignatedPath
    subgoals: SubgoalTracker
    _previous: Choice | None
    _situation: Situation | None
    _straight_speed: float | None
    _outrun_seen_s: float

    def _choose(
        self,
        checks: LegChecks,
        speeds: np.ndarray,
        nominal_index: int,
        previous: Choice | None,
        only_way: Way | None = None,
    ) -> Chosen | None: ...
    def _straight(self, checks: LegChecks, speed: float) -> Chosen | None: ...
    def _inside_shield(self, plan: Plan) -> bool: ...
    def _command(self, situation: Situation, plan: Plan) -> Command: ...
    def _slow_checks(self, checks: LegChecks) -> LegChecks: ...


def straight_plan(checks: LegChecks, speed: float) -> Plan:
    """The straight leg from the robot to the subgoal at ``speed`` (paper step 1's plan)."""
    return Plan(
        "straight",
        speed,
        checks.subgoal.copy(),
        waypoints=np.array([checks.position, checks.subgoal]),
        subgoal_index=checks.subgoal_index,
        candidate_count=1,
        chosen=0,
    )


def straight_chosen(plan: Plan) -> Chosen:
    return Chosen(Choice(Way(STRAIGHT, 0, 0), int(round(plan.speed_mps * 1000))), plan, None)


def cost_terms(
    breakdown: Callable[[int], dict[str, float]], order: Sequence[int] | np.ndarray, rank: int, total: np.ndarray
) -> dict[str, Any]:
    """Each critic's share of E for the chosen candidate and the cheapest other one (for tuning and views);
    ``breakdown(k)``: candidate k's terms by critic name, and "total"."""
    best = int(order[rank])
    other = int(order[1] if rank == 0 else order[0]) if len(order) > 1 else None
    runner_up = breakdown(other) if other is not None and math.isfinite(total[other]) else None
    return {"chosen": breakdown(best), "runner_up": runner_up}
