"""Any planner behind the shield, untouched: ``ShieldedPlanner(inner)`` is itself a planner (docs/design.md §7).

Each cycle it calls the inner planner, filters the command through :class:`~viapath.safety.Shield`
and returns the inner decision with the filtered command; the plan keeps what the inner planner
intended and records the shield's verdict in ``plan.extras["shield"]`` (intervened, reason, the
original command, ...). It counts the cycles it intervened in, per episode (``episode_metrics``).

Choice: the shield is on by default for ``viapath`` only (``SHIELDED_BY_DEFAULT``): the baselines
and navground peers are benchmarked as their authors define them unless asked otherwise.
"""

from __future__ import annotations

from typing import Any

from viapath.observation import Decision, Observation, Plan
from viapath.path import SubgoalTracker
from viapath.planning.base import Planner
from viapath.safety.shield import Shield, ShieldConfig

SHIELDED_BY_DEFAULT = frozenset({"viapath"})


def shield_default(planner_name: str) -> bool:
    """Whether ``viapath run/bench`` shield this planner when ``--shield`` is not given."""
    return planner_name in SHIELDED_BY_DEFAULT


class ShieldedPlanner(Planner):
    """The inner planner's decisions, with every command made passively safe."""

    shield: Shield

    def __init__(self, inner: Planner, dt_s: float = 0.1, config: ShieldConfig | None = None) -> None:
        # No super().__init__: the inner planner owns the path, limits and subgoal tracking.
        self.inner = inner
        self.path = inner.path
        self.nominal_speed_mps = inner.nominal_speed_mps
        self.limits = inner.limits
        self.robot_radius_m = inner.robot_radius_m
        self.subgoal_policy = inner.subgoal_policy
        self.settings = inner.settings
        self.shield = Shield(inner.limits, dt_s, config)
        inner.shield = self.shield  # a planner that plans inside the shield reads it
        self.interventions = 0
        self.cycles = 0

    @property
    def name(self) -> str:  # type: ignore[override]
        return self.inner.name

    @property
    def subgoals(self) -> SubgoalTracker:  # type: ignore[override]
        return self.inner.subgoals

    def reset(self) -> None:
        self.inner.reset()
        self.interventions = 0
        self.cycles = 0

    def plan(self, observation: Observation) -> Decision:
        self.shield.corridor = self.inner.path  # the path may change between cycles (a new one from ROS 2)
        with self.shield.remembering():  # the planner's own test of its command is the filter's first
            decision = self.inner.plan(observation)
            result = self.shield.filter(observation, decision.command)
        self.cycles += 1
        self.interventions += int(result.intervened)
        plan: Plan = decision.plan
        plan.extras["shield"] = result.as_dict()
        return Decision(result.command, plan)

    def episode_metrics(self) -> dict[str, Any]:
        return {
            "shield": self.shield.config.enabled,
            "shield_mode": self.shield.config.mode,
            "shield_interventions": self.interventions,
        }


def shielded(
    planner: Planner,
    shield: bool | None,
    dt_s: float,
    options: dict[str, Any] | None = None,
    planner_name: str | None = None,
) -> Planner:
    """``planner`` behind the shield when ``shield`` says so (None: the planner's default, see
    :func:`shield_default`); ``options`` are shield options (``SHIELD_OPTIONS`` names)."""
    name = planner_name or planner.name
    config = ShieldConfig.from_options(options)
    on = shield_default(name) if shield is None else bool(shield)
    if not on or not config.enabled:
        return planner
    return ShieldedPlanner(planner, dt_s, config)
