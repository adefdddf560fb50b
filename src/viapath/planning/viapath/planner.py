"""The paper's planner, as its procedure: situation → candidates → costs → the first candidate the
robot can follow → command; with no free candidate, stop or escape.

Source: Yamada, Sa, Ohya, §3 (procedure steps 1-5, Eq. 1), after Tsubouchi et al.; DESIGN §2. Each
step is a module of this package, named after it:

1. situation (:mod:`.checks`): the subgoal, the people with their capped uncertainty cones, the corridor;
2. candidates (:mod:`.candidates`): for every speed of the set (:meth:`ViaPathPlanner.speed_set`), the
   straight leg, via points chained through further obstacles, slow/wait, the way back through the
   path's corners (paper step 1: a free straight leg at the nominal speed is the plan at once);
3. costs (:mod:`.critics`): Eq. 1 as critics, plus side preference and hysteresis;
4. follow (:mod:`.follow`): the cheapest candidate whose first leg the robot can follow within its
   motion limits and, with a shield behind the planner (DESIGN §7), whose command the shield admits
   (via points then also keep the robot's braking envelope from people);
5. command: steer for the plan's target at the plan's speed (turning on the spot first if needed);
6. escape (:mod:`.escape`): stop if standing is safe, else the drive command that stays clear longest.

What the paper leaves open and we chose, beyond what those modules say:
* The speed set is the configured speeds, the current speed and the nominal speed (mm/s resolution,
  within the speed limit).
* Constraint hysteresis (``keep_previous_way``): under velocity noise last cycle's way round often
  looks blocked for one cycle only because its inflation grew with the estimate's error; the plan
  then flips and flips back. If last cycle's way is gone, it is searched for once more with
  ``keep_previous_inflation`` of the uncertainty inflation (the safety margin stays) and kept if,
  with the usual hysteresis, it still costs less than the new choice.
* Staying ahead of someone catching up from behind (``outrun_hold_s``, 1 s; 0 in the preset ``paper``):
  Eq. 1's time term makes the fastest free straight leg the cheapest, and step 1 takes the nominal leg
  back as soon as it is free over the horizon, so the robot flipped between the top speed and nominal
  every few cycles at the horizon's edge. When the straight leg at nominal is blocked by someone from
  behind whom the top speed outruns, the straight leg faster than nominal is at the slowest speed
  whose leg stays free ``outrun_hold_s`` past the horizon, and the robot goes back to a slower one only
  when that leg stays free that long too, and not to nominal within ``outrun_hold_s`` of last seeing
  someone to outrun (under noise the nominal leg looks free in single cycles). Someone faster than the
  top speed can only be raced to the subgoal, and there the cheapest (fastest) leg keeps the most
  margin: unchanged.
* **Static obstacles** (DESIGN §10; the paper draws its path boundary round static things and plans for
  moving ones only). A static obstacle is a vertical prism in x-y-t: the guarded entry hands the planner
  the observation's static layer as discs of velocity 0 sampled along its segments (within a few mm of
  the segments' capsules, :mod:`viapath.static`), so the legs are checked against it exactly as against
  people (a cylinder of velocity 0 is the prism), and the same via-point code makes its avoiding lines
  (v_i = 0: t* = |w|/v). What is ours: (1) via points go round a whole **shape**, not the one disc a leg
  met first: a pair (node, static disc) becomes the two discs of that disc's shape that reach furthest
  left and right as seen from the node (the tangents to the shape's inflated outline,
  :func:`.candidates._round_static_shapes`), and the root branches once per shape; a node hugging a
  shape slides along it instead of creeping round its nearest disc (:func:`.candidates._with_slides`);
  (2) static legs are checked to their end, past the horizon (a leg into a wall is not made free by
  driving it slowly), and without the shield's braking envelope, which is for where people may walk;
  (3) static discs farther outside the corridor than their reach are left out of the cycle (no
  candidate can meet them); (4) a **closed way** (no free candidate, standing is safe, and the straight
  leg to the subgoal meets static geometry before any person) is not a plain stop: the robot drives on along that leg to
  ``blocked_gap_m`` short of touching it, at a speed from which it stops there, and waits with status
  ``blocked``; every cycle looks again, so it goes on when the door opens. The candidate tree of a
  cycle with static geometry runs the numpy recipe with the compiled leg checks and via points
  (:data:`viapath.compiled.arithmetic.STEPWISE`): the shapes' extremes are not compiled. Its escape, which
  treats static discs as any obstacle, keeps the whole-step kernels (:func:`escape_step`).
* The way back (``return_lookahead_m``, 0.5 m by default; 0 in the preset ``paper``): off the path
  line, the paper's step 1 is tried first towards the path point that far ahead instead of the
  subgoal. The paper heads for the subgoal; when that is metres away the robot drifts back to the path
  on a shallow line after a pass, and that drift was most of the extra deviation of a passing robot
  (docs/weights.md §6).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, cast

import numpy as np
from numpy.typing import ArrayLike

from viapath.compiled import numba_available
from viapath.compiled import resolve as resolve_compute
from viapath.compiled import slots as slot
from viapath.compiled.arithmetic import STEPWISE, Arithmetic, NodeStore, arithmetic_for, whole_steps_compiled
from viapath.geometry import wrap_angle
from viapath.observation import Command, MotionLimits, Observation, Obstacles, RobotState
from viapath.options import Settings
from viapath.path import DesignatedPath
from viapath.planning.base import Decision, Inflation, Plan, Planner, Situation
from viapath.planning.viapath.candidates import STRAIGHT, Candidates, Choice, RootLegs, Way, _candidates_of, grow
from viapath.planning.viapath.checks import LegChecks
from viapath.planning.viapath.critics import PAPER_CRITICS, Context, critics_for, score
from viapath.planning.viapath.escape import escape_fan, stop_or_escape
from viapath.planning.viapath.follow import can_follow, follows
from viapath.planning.viapath.options import VIAPATH_OPTIONS

if TYPE_CHECKING:
    from viapath.planning.viapath.critics import Distance, Heading, Hysteresis, SidePreference, SpeedError, Time


class _CompiledCandidates:
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
class _Chosen:
    choice: Choice
    plan: Plan
    # None for the paper's step 1 (a free straight leg at nominal speed)
    candidates: Candidates | _CompiledCandidates | None


class ViaPathPlanner(Planner, name="viapath"):
    """Yamada-Sa-Ohya planner: follows the designated path, avoids by changing speed and direction."""

    options = VIAPATH_OPTIONS

    def __init__(self, path: DesignatedPath, *, config: Mapping[str, Any] | None = None, **kwargs: Any) -> None:
        if config is not None:  # a mapping of options (e.g. ViaPathConfig(...)), before any keyword
            kwargs["options"] = {**dict(config), **dict(kwargs.get("options") or {})}
        super().__init__(path, **kwargs)
        self.config = self.settings
        self.critics = critics_for(self.config)
        self.arithmetic = arithmetic_for(self.config.compute)  # numpy reference or compiled kernels (docs/speed.md)
        self._previous: Choice | None = None
        self._previous_escape: Command | None = None  # last cycle's command, if it escaped
        self._situation: Situation | None = None  # this cycle's, for the shield check of candidates
        self._last_command: tuple[Any, ...] | None = None  # (situation, plan, command) of the last command made
        self._straight_speed: float | None = None  # last cycle's speed if its plan was the straight leg
        self._outrun_seen_s = -math.inf  # when someone from behind last blocked the nominal leg (outrun)

    @classmethod
    def resolved_defaults(cls) -> dict[str, str]:
        """What the default of an option resolves to here (``viapath planners viapath`` shows it)."""
        return {"compute": resolve_compute(cls.options.defaults()["compute"])}

    def reset(self) -> None:
        super().reset()
        self._previous = None
        self._previous_escape = None
        self._last_command = None
        self._straight_speed = None
        self._outrun_seen_s = -math.inf

    # -- the recipe ----------------------------------------------------------------------------------

    def decide(self, situation: Situation) -> Decision:
        decision = self._decide(situation)
        decision.plan.extras["backend"] = self.arithmetic.name
        plan = decision.plan
        self._straight_speed = plan.speed_mps if plan.status == "straight" else None
        return decision

    def _decide(self, situation: Situation) -> Decision:
        if situation.obstacles.static_mask is not None:
            situation = self._near_corridor(situation)
        self._situation = situation
        checks = LegChecks.of(
            situation,
            self.config,
            self.subgoals,
            self.subgoal_policy,
            self.robot_radius_m,
            self._cycle_arithmetic(situation),
        )
        if self.shield is not None and self.shield.config.enabled:
            # Set on the checks just built (dataclasses.replace would copy every field again, every cycle).
            checks.envelope_accel_mps2 = self.shield.config.person_accel_mps2
            checks.envelope_period_s = self.shield.dt_s
            checks.max_accel_mps2 = self.limits.max_accel_mps2
        speeds, nominal_index = self.speed_set(situation.robot.speed_mps)
        chosen = self._choose(checks, speeds, nominal_index, self._previous)
        if chosen is None:
            self._previous = None
            decision = escape_step(checks, self.limits, self.config, self._previous_escape, self.arithmetic)
            self._previous_escape = decision.command if decision.plan.status == "escape" else None
            if decision.plan.status == "stop" and checks.obstacles.static_mask is not None:
                return self._blocked(situation, checks, float(speeds[nominal_index])) or decision
            return decision
        self._previous_escape = None
        if self.config.keep_previous_way and self._previous is not None:
            chosen = self._keep_previous_way(chosen, checks, speeds, nominal_index)
        self._previous = chosen.choice
        return Decision(self._command(situation, chosen.plan), chosen.plan)

    def _near_corridor(self, situation: Situation) -> Situation:
        """The situation without the static discs no candidate can meet: every leg of a candidate stays in the
        corridor (or within the escape's bound of it), so a static disc farther outside than its check
        radius cannot touch one. Walls of other rooms cost nothing then."""
        obstacles, inflation = situation.obstacles, situation.inflation
        reach = inflation.check_radii + max(situation.corridor_tolerance_m, self.config.escape_max_excess_m)
        far = obstacles.is_static & (self.path.corridor_excess(obstacles.positions) > reach)
        if not far.any():
            return situation
        keep = ~far
        kept = Inflation(
            *(
                getattr(inflation, name)[keep]
                for name in ("obstacle_radii_m", "check_radii", "growth", "growth_until_s")
            )
        )
        return dataclasses.replace(situation, obstacles=obstacles.subset(keep), inflation=kept)

    def _cycle_arithmetic(self, situation: Situation) -> Any:
        """The arithmetic of this cycle: with static geometry in view the candidate tree runs on the numpy
        recipe (the extremes of static shapes, :func:`.candidates._round_static_shapes`, are not compiled),
        its leg checks and via points still on the compiled kernels when they are there."""
        arithmetic = self.arithmetic
        if situation.obstacles.static_mask is None or not arithmetic.whole_steps or arithmetic.name == "numpy":
            return arithmetic
        return STEPWISE.get(arithmetic.name, arithmetic)

    def _blocked(self, situation: Situation, checks: LegChecks, speed_mps: float) -> Decision | None:
        """No candidate is free and standing is safe: if static geometry closes the way to the subgoal (a
        closed door, a wall across the corridor) and nothing else meets the straight leg before it, drive on
        along that leg to ``blocked_gap_m`` short of where the robot would touch it, at a speed from which
        it stops there, and wait; status ``blocked``. Each cycle looks again, so the robot goes on when
        the way opens. None when people block the way first (the caller's stop stands)."""
        position, subgoal = checks.position, checks.subgoal
        offset = subgoal - position
        length = float(np.hypot(*offset))
        if length < 1e-6:
            return None
        direction = offset / length
        contact = checks.contact_times(
            position[None], np.zeros(1), direction[None] * speed_mps, np.array([length / speed_mps]), np.inf
        )[0]
        first = int(np.argmin(contact))
        if not (math.isfinite(contact[first]) and checks.obstacles.is_static[first]):
            return None
        ahead_m = max(0.0, speed_mps * float(contact[first]) - self.config.blocked_gap_m)
        stop_at = position + direction * ahead_m
        speed = min(speed_mps, math.sqrt(self.limits.max_accel_mps2 * ahead_m))
        if speed < 0.02 or ahead_m < 0.02:
            speed, stop_at = 0.0, position.copy()
        elif not (
            checks.legs_free(position[None], np.zeros(1), direction[None] * speed, np.array([ahead_m / speed]))[0]
            and checks.legs_inside(position[None], stop_at[None])[0]
        ):
            return None
        plan = Plan(
            "blocked",
            speed,
            stop_at,
            waypoints=np.array([position, stop_at]),
            subgoal_index=checks.subgoal_index,
            extras={"blocked": f"static geometry closes the way {speed_mps * float(contact[first]):.2f} m ahead"},
        )
        command = Command.stop() if speed == 0.0 else self._command(situation, plan)
        return Decision(command, plan)

    def speed_set(self, current_speed_mps: float) -> tuple[np.ndarray, int]:
        """The configured speeds, the current speed and the nominal speed (mm/s resolution, within
        the limit), sorted; and where the nominal speed is in it."""
        top = self.limits.max_speed_mps
        current = round(min(current_speed_mps, top), 3) if current_speed_mps > 0.02 else None
        # The same few sets come back cycle after cycle (one per current speed in mm/s): kept while the
        # options, limits and nominal speed are the same objects.
        config, limits, nominal_speed = self.config, self.limits, self.nominal_speed_mps
        cached = self.__dict__.get("_speed_sets")
        if cached is None or cached[0] is not config or cached[1] is not limits or cached[2] is not nominal_speed:
            cached = self.__dict__["_speed_sets"] = (config, limits, nominal_speed, {})
        known: dict[float | None, tuple[list[float], int]] = cached[3]
        found = known.get(current)
        if found is None:
            nominal = self.nominal_in_speed_set_mps()
            speeds = {round(min(v, top), 3) for v in self.config.speeds} | {nominal}
            if current is not None:
                speeds.add(current)
            ordered = sorted(speeds)
            found = known[current] = (ordered, ordered.index(nominal))
            if len(known) > 4096:  # a long run through many current speeds: start again
                known.clear()
        return np.array(found[0]), found[1]

    def nominal_in_speed_set_mps(self) -> float:
        return round(min(self.nominal_speed_mps, self.limits.max_speed_mps), 3)

    def _choose(
        self,
        checks: LegChecks,
        speeds: np.ndarray,
        nominal_index: int,
        previous: Choice | None,
        only_way: Way | None = None,
    ) -> _Chosen | None:
        """Candidates → costs → the cheapest the robot can follow; None when none is free.
        With ``only_way``, only candidates going that way round are considered. Staying ahead of someone
        catching up from behind, the straight leg's speed is the slowest that holds (:meth:`_outrun`)."""
        outrun = only_way is None and self.config.outrun_hold_s > 0
        if outrun and self._straight_speed is not None:
            held = self._outrun_held(checks, speeds, nominal_index)
            if held is not None:
                return held
        chosen = self._cheapest(checks, speeds, nominal_index, previous, only_way)
        if outrun and chosen is not None:
            return self._outrun(checks, speeds, nominal_index, chosen) or chosen
        return chosen

    def _cheapest(
        self,
        checks: LegChecks,
        speeds: np.ndarray,
        nominal_index: int,
        previous: Choice | None,
        only_way: Way | None = None,
    ) -> _Chosen | None:
        """Paper steps 1-4 (:meth:`_choose` without the speed of outrunning)."""
        if only_way is None and self.config.return_lookahead_m > 0:
            back = self._way_back(checks, float(speeds[nominal_index]))
            if back is not None:
                return back
        if checks.arithmetic is self.arithmetic and self._compiled_choice():
            return self._choose_compiled(checks, speeds, nominal_index, previous, only_way)
        roots = RootLegs.of(checks, speeds, nominal_index)
        if roots.nominal_is_free and only_way is None:
            # Paper step 1: a free straight path at the normal speed is the plan, if the robot can
            # turn onto it in time.
            straight = self._straight(checks, float(speeds[nominal_index]))
            if straight is not None:
                return straight
        candidates = grow_step(checks, roots, self.config, self._slow_checks(checks))
        if candidates is None:
            return None
        costs = score(candidates, self.critics, Context(checks.heading_rad, self.nominal_speed_mps, previous))
        total = costs.total
        if only_way is not None:
            total = np.where(only_way.same(candidates.ways), total, np.inf)
            if not np.isfinite(total).any():
                return None
        polylines = [candidates.polyline(k) for k in range(len(candidates))] if self.config.record_candidates else []
        order = total.argsort(kind="stable")
        for rank, best in enumerate(order[: self.config.max_rollouts]):
            if not np.isfinite(total[best]):
                break
            # can_follow's verdict before the plan is made: in a cycle without a free candidate (the slowest
            # cycles) every plan would be made for nothing.
            followed, turn_in_place = follows(*candidates.first_leg(int(best)), checks, self.limits, self.config)
            if not followed:
                continue
            plan = self._plan_of(candidates, int(best), total, checks, polylines)
            if turn_in_place:
                plan.extras["turn_in_place"] = True
            if self._inside_shield(plan):
                plan.extras["cost_terms"] = _cost_terms(costs.breakdown, order, rank, total)
                ways = candidates.ways[best]
                choice = Choice(Way(int(ways[0]), int(ways[1]), int(ways[2])), int(candidates.speed_mmps[best]))
                return _Chosen(choice, plan, candidates)
        return None

    # -- the same choice in two compiled calls (docs/CHANGELOG-speed.md, "The compiled cycle") -------------------------

    def _compiled_choice(self) -> bool:
        """Whether :meth:`_choose` runs as :meth:`_choose_compiled`: the compiled whole-step kernels, the
        paper's critics (the kernel sums exactly those) and no candidate polylines to record."""
        arithmetic, config, critics = self.arithmetic, self.config, self.critics
        cached = self.__dict__.get(
            "_compiled_choice_of"
        )  # (arithmetic, options, critics, the answer): every cycle asks
        if cached is None or cached[0] is not arithmetic or cached[1] is not config or cached[2] is not critics:
            answer = (
                arithmetic.name == "numba"
                and arithmetic.whole_steps
                and not config.record_candidates
                and tuple(map(type, critics)) == PAPER_CRITICS
            )
            cached = self.__dict__["_compiled_choice_of"] = (arithmetic, config, critics, answer)
        return cached[3]

    def _kernel_constants(self) -> tuple[Any, ...]:
        """The kernels' settings that do not change within an episode (rebuilt when the options, limits or
        critics object is replaced); their slots: :mod:`viapath.compiled.slots`."""
        config, limits, critics, nominal_speed = self.config, self.limits, self.critics, self.nominal_speed_mps
        cached = self.__dict__.get("_kernel_cache")
        if (
            cached is not None
            and cached[0] is config
            and cached[1] is limits
            and cached[2] is critics
            and cached[3] is nominal_speed
        ):
            return cached[4]
        distance, time, speed, heading, side, hysteresis = cast(
            "tuple[Distance, Time, SpeedError, Heading, SidePreference, Hysteresis]", self.critics
        )  # the paper's critics (PAPER_CRITICS): the only ones the kernels take
        settings = np.zeros(slot.F_COUNT, dtype=np.float64)
        settings[[slot.F_K1, slot.F_K2, slot.F_K3, slot.F_K4, slot.F_SIDE, slot.F_HYSTERESIS]] = (
            distance.weight,
            time.weight,
            speed.weight,
            heading.weight,
            side.weight,
            hysteresis.weight,
        )
        settings[slot.F_NOMINAL] = self.nominal_speed_mps
        settings[slot.F_ROLLOUT_HEADING] = config.rollout_heading_rad
        settings[slot.F_ACCEL] = limits.max_accel_mps2
        settings[slot.F_DT] = config.rollout_dt_s
        settings[slot.F_TURN_RATE] = limits.max_turn_rate_radps
        settings[slot.F_TURN_ACCEL] = limits.max_turn_accel_radps2
        settings[slot.F_SPEED] = limits.max_speed_mps
        settings[slot.F_GAIN] = config.heading_gain
        settings[slot.F_TURN_IN_PLACE] = config.turn_in_place_min_rad
        settings[slot.F_SPACING] = config.corridor_check_spacing_m
        settings[slot.F_STANDING] = speed.standing_per_s
        settings[slot.F_CREEP] = config.creep_speed_mps
        integers = np.zeros(slot.C_COUNT, dtype=np.int64)
        integers[slot.C_DEPTH] = config.max_depth
        integers[slot.C_ROOT_LIMIT] = config.max_root_obstacles
        integers[slot.C_ROLLOUTS] = config.max_rollouts
        integers[slot.C_STEPS] = max(1, int(round(config.rollout_s / config.rollout_dt_s)))
        integers[slot.C_DEGREES] = heading.degrees
        integers[slot.C_PREFERRED] = side.preferred
        integers[slot.C_SLOW] = bool(config.slow_times_s)
        slow_times = np.asarray(config.slow_times_s, dtype=np.float64).reshape(-1)
        constants = (settings, integers, slow_times)
        self.__dict__["_kernel_cache"] = (config, limits, critics, nominal_speed, constants)
        return constants

    def _choose_compiled(
        self, checks: LegChecks, speeds: np.ndarray, nominal_index: int, previous: Choice | None, only_way: Way | None
    ) -> _Chosen | None:
        """:meth:`_choose` with one kernel doing everything up to the shield check (:func:`viapath.compiled.planning.choose`): it
        rolls out candidates cheapest first until one follows; a candidate the shield refuses sends the search
        on to the next ones here, as the reference does."""
        constants, integers_0, slow_times = self._kernel_constants()
        settings = constants.copy()  # with this cycle's entries:
        settings[slot.F_STOP_SHORT] = checks.stop_short_m
        settings[slot.F_HORIZON] = checks.horizon_s
        settings[slot.F_TOLERANCE] = checks.corridor_tolerance_m
        integers = integers_0.copy()  # (one item at a time: a slice from a tuple converts it first, slower)
        index = checks.subgoal_index
        integers[slot.C_NOMINAL] = nominal_index
        if index >= 2:  # the robot's segment matters only when a corner can lie between it and the subgoal
            integers[slot.C_SEGMENT] = int(checks.path.project(checks.position)[0])
        integers[slot.C_SUBGOAL] = index
        integers[slot.C_TRY_STRAIGHT] = 1
        if previous is not None:
            way = previous.way
            integers[slot.C_PREVIOUS] = 1
            integers[slot.C_PREV_OBSTACLE] = way.obstacle
            integers[slot.C_PREV_SIDE] = way.side
            integers[slot.C_PREV_ROOT] = way.root
            integers[slot.C_PREV_MMPS] = previous.speed_mmps
        if only_way is not None:
            integers[slot.C_ONLY] = 1
            integers[slot.C_ONLY_OBSTACLE] = only_way.obstacle
            integers[slot.C_ONLY_SIDE] = only_way.side
            integers[slot.C_ONLY_ROOT] = only_way.root
        slow_checks = self._slow_checks(checks)
        arithmetic = self.arithmetic
        chosen = arithmetic.choose(checks, slow_checks, speeds, slow_times, settings, integers)
        if chosen.status == slot.STEP_ONE:
            plan = _straight_plan(checks, float(speeds[nominal_index]))
            if chosen.turn_in_place:
                plan.extras["turn_in_place"] = True
            if self._inside_shield(plan):
                return _straight_chosen(plan)
            integers[slot.C_TRY_STRAIGHT] = 0  # the shield refused it: the candidates decide
            chosen = arithmetic.choose(checks, slow_checks, speeds, slow_times, settings, integers)
        if chosen.status != slot.CANDIDATES or chosen.first < 0:  # first: the ranks before it do not follow
            return None
        leaves, order, follow, total, store = chosen.leaves, chosen.order, chosen.follow, chosen.total, chosen.store
        for rank in range(chosen.first, min(len(order), self.config.max_rollouts)):
            best = order[rank]
            if not math.isfinite(total[best]):
                break
            verdict = follow[rank]
            if verdict == 0:
                continue
            plan = self._plan_of_nodes(store, leaves, best, total, checks)
            if verdict < 0:  # past the first that follows: only after the shield refused that one
                verdict = can_follow(plan, checks, self.limits, self.config)
            elif verdict == 2:
                plan.extras["turn_in_place"] = True
            if verdict and self._inside_shield(plan):
                plan.extras["cost_terms"] = _cost_terms(self._cost_breakdown(chosen.terms), order, rank, total)
                node = int(leaves[best])
                way, speed = store.way(node), store.speed(node)
                return _Chosen(
                    Choice(Way(*way), int(round(speed * 1000))),
                    plan,
                    _CompiledCandidates(store, leaves, checks.subgoal),
                )
        return None

    def _cost_breakdown(self, terms: np.ndarray) -> Callable[[int], dict[str, float]]:
        """:meth:`.critics.Costs.breakdown` for :func:`viapath.compiled.planning.choose`'s costs (rows: the critics' terms,
        E): one column as Python floats, the same values as the numpy path's."""
        critics = self.critics
        cached = self.__dict__.get("_cost_names")
        if cached is None or cached[0] is not critics:
            cached = self.__dict__["_cost_names"] = (critics, tuple(critic.name for critic in critics) + ("total",))
        names = cached[1]
        return lambda k: dict(zip(names, terms[:, k].tolist()))

    def _plan_of_nodes(
        self, store: NodeStore, leaves: np.ndarray, k: int, total: np.ndarray, checks: LegChecks
    ) -> Plan:
        """:meth:`_plan_of` from the compiled tree's node store."""
        node = int(leaves[k])
        speed_after, slow_s, slow_speed = store.slowing(node)
        if slow_s > 0:
            return Plan(
                "wait" if slow_speed == 0.0 else "slow",
                slow_speed,
                checks.subgoal.copy(),
                waypoints=np.array([checks.position, checks.subgoal]),
                subgoal_index=checks.subgoal_index,
                candidate_count=len(leaves),
                candidate_costs=total,
                candidate_polylines=[],
                chosen=k,
                extras={"slow_s": slow_s, "speed_after_mps": speed_after},
            )
        points = [checks.subgoal]
        while node >= 0:
            points.append(store.position(node))
            node = store.parent(node)
        line = np.array(points[::-1])
        return Plan(
            "avoid" if len(line) > 2 else "straight",
            speed_after,
            line[1].copy(),
            via_points=line[1:-1].copy(),
            waypoints=line,
            subgoal_index=checks.subgoal_index,
            candidate_count=len(leaves),
            candidate_costs=total,
            candidate_polylines=[],
            chosen=k,
        )

    def _straight(self, checks: LegChecks, speed: float) -> _Chosen | None:
        """The straight leg to the subgoal at ``speed`` as the plan, if the robot can turn onto it in time
        (and the shield admits its command); its freedom is the caller's to check."""
        plan = _straight_plan(checks, speed)
        if can_follow(plan, checks, self.limits, self.config) and self._inside_shield(plan):
            return _straight_chosen(plan)
        return None

    # -- staying ahead of someone from behind (``outrun_hold_s``) ---------------------------------------

    def _outrun_held(self, checks: LegChecks, speeds: np.ndarray, nominal_index: int) -> _Chosen | None:
        """Last cycle drove the straight leg faster than nominal and the nominal leg is free again, but
        only just: someone from behind would catch it within ``outrun_hold_s`` past the horizon. Then
        the slowest straight speed from nominal up whose leg is free that long (None: the usual choice).
        Free that long too, the robot still keeps above nominal for ``outrun_hold_s`` after it last saw
        someone to outrun. Without this the robot drops to nominal, is caught up with within a few
        cycles, speeds up again: a speed flip every half second at the horizon's edge."""
        nominal = float(speeds[nominal_index])
        if cast(float, self._straight_speed) <= nominal + 1e-9:
            return None
        lookahead = self.config.return_lookahead_m
        if lookahead > 0 and checks.back_to_path(lookahead) is not None:
            return None  # off the path line: the way back (:meth:`_way_back`) comes first
        at_nominal = np.array([nominal])
        if not checks.goal_legs(checks.position[None], np.zeros(1), at_nominal)[2][0]:
            return None
        hold = checks.horizon_s + self.config.outrun_hold_s
        direction, _, free, contact = checks.goal_legs(checks.position[None], np.zeros(1), at_nominal, hold)
        if free[0]:
            # Free that long too: back to nominal, unless someone was being outrun within the hold (under
            # noise the nominal leg looks free in single cycles while the person still comes on).
            recently = self._now() - self._outrun_seen_s < self.config.outrun_hold_s
            return self._slowest_holding(checks, speeds[nominal_index + 1 :]) if recently else None
        if not self._catching_up(checks, direction[0], contact[0], nominal, float(speeds[-1])):
            return None
        self._outrun_seen_s = self._now()
        return self._slowest_holding(checks, speeds[nominal_index:])

    def _outrun(self, checks: LegChecks, speeds: np.ndarray, nominal_index: int, chosen: _Chosen) -> _Chosen | None:
        """The cheapest plan is the straight leg faster than nominal, and the nominal leg is blocked by
        someone catching up from behind whom the top speed outruns: the slowest faster straight speed
        whose leg stays free ``outrun_hold_s`` past the horizon instead (None: keep ``chosen``). Eq. 1's
        time term prefers the fastest, from which the robot would drop back to nominal as soon as that
        leg is free, and so on."""
        plan, nominal = chosen.plan, float(speeds[nominal_index])
        if plan.status != "straight" or len(plan.waypoints) != 2 or plan.speed_mps <= nominal + 1e-9:
            return None
        direction, _, _, contact = checks.goal_legs(checks.position[None], np.zeros(1), np.array([nominal]))
        if not self._catching_up(checks, direction[0], contact[0], nominal, float(speeds[-1])):
            return None
        self._outrun_seen_s = self._now()
        slower = speeds[(speeds > nominal + 1e-9) & (speeds < plan.speed_mps - 1e-9)]
        return self._slowest_holding(checks, slower) if len(slower) else None

    def _now(self) -> float:
        return float(cast(Situation, self._situation).observation.time_s)

    @staticmethod
    def _catching_up(checks: LegChecks, direction: np.ndarray, contact: np.ndarray, nominal: float, top: float) -> bool:
        """Whether the first obstacle the straight leg meets (``contact``: its contact times) is behind the
        robot, coming along the leg faster than ``nominal`` and slower than ``top`` (one to outrun)."""
        if not np.isfinite(contact).any():
            return False
        first = int(np.argmin(contact))
        obstacles = checks.obstacles
        behind = float((obstacles.positions[first] - checks.position) @ direction) < 0
        along = float(obstacles.velocities[first] @ direction)
        return behind and nominal < along < top

    def _slowest_holding(self, checks: LegChecks, speeds: np.ndarray) -> _Chosen | None:
        """The straight leg at the slowest of ``speeds`` (ascending) whose leg is free ``outrun_hold_s``
        past the horizon, if the robot can follow it (None: the first such cannot, or none is free)."""
        hold = checks.horizon_s + self.config.outrun_hold_s
        speeds = np.asarray(speeds, dtype=float)
        starts = checks.position[None].repeat(len(speeds), axis=0)
        _, _, free, _ = checks.goal_legs(starts, np.zeros(len(speeds)), speeds, hold)
        if not free.any():
            return None
        return self._straight(checks, float(speeds[int(np.argmax(free))]))

    def _way_back(self, checks: LegChecks, speed: float) -> _Chosen | None:
        """Beyond the paper (``return_lookahead_m``): off the path line, the paper's step 1 towards the
        path point ``return_lookahead_m`` ahead instead of the subgoal, i.e. the free straight leg at the
        nominal speed, checked on along the path to the subgoal. None if there is none; then the paper's
        candidates decide. Eq. 1 never picks such a leg itself: it turns more (k4·θ) than the leg to a
        far subgoal and nothing in E rewards being on the path, so after a pass the robot would drift
        back on the shallow line to a subgoal metres away (docs/weights.md §6)."""
        back = checks.back_to_path(self.config.return_lookahead_m)
        if back is None:
            return None
        _, _, free, _ = back.goal_legs(back.position[None], np.zeros(1), np.array([speed]))
        if not free[0]:
            return None
        plan = Plan(
            "straight",
            speed,
            back.subgoal.copy(),
            waypoints=np.array([back.position, back.subgoal, checks.subgoal]),
            subgoal_index=checks.subgoal_index,
            candidate_count=1,
            chosen=0,
            extras={"way_back": True},
        )
        if not (can_follow(plan, back, self.limits, self.config) and self._inside_shield(plan)):
            return None
        return _Chosen(Choice(Way(STRAIGHT, 0, 0), int(round(speed * 1000))), plan, None)

    def _inside_shield(self, plan: Plan) -> bool:
        """With a shield (DESIGN §7) behind the planner, a candidate whose command the shield would refuse
        is passed over for the next one: speeds near a person only where the robot can stop in time."""
        if self.shield is None:
            return True
        situation = cast(Situation, self._situation)  # set by this cycle's plan before any candidate is checked
        command = self._command(situation, plan)
        verdict = self.shield.evaluate(situation.observation, np.array([[command.speed_mps, command.turn_rate_radps]]))
        ok = verdict["friendly"] if self.shield.config.mode == "passive-friendly" else verdict["admissible"]
        if not ok[0]:
            plan.extras["outside_shield"] = True
        return bool(ok[0])

    def _plan_of(
        self, candidates: Candidates, k: int, total: np.ndarray, checks: LegChecks, polylines: list[np.ndarray]
    ) -> Plan:
        common: dict[str, Any] = dict(
            subgoal_index=checks.subgoal_index,
            candidate_count=len(candidates),
            candidate_costs=total,
            candidate_polylines=polylines,
            chosen=k,
        )
        target, speed = candidates.first_leg(k)
        if candidates.slow_s[k] > 0:
            return Plan(
                "wait" if speed == 0.0 else "slow",
                speed,
                target.copy(),
                waypoints=np.array([checks.position, checks.subgoal]),
                extras={"slow_s": float(candidates.slow_s[k]), "speed_after_mps": float(candidates.speed_mps[k])},
                **common,
            )
        line = candidates.polyline(k)
        return Plan(
            "avoid" if len(line) > 2 else "straight",
            speed,
            target.copy(),
            via_points=line[1:-1].copy(),
            waypoints=line,
            **common,
        )

    def _slow_checks(self, checks: LegChecks) -> LegChecks:
        fraction = self.config.slow_leg_inflation
        # (np.logical_or.reduce: what .any() answers, NaN counting as not zero, without .any()'s Python wrapper)
        any_nonzero = np.logical_or.reduce
        if fraction >= 1.0 or not (
            any_nonzero(checks.obstacles.position_sigma_m) or any_nonzero(checks.obstacles.velocity_sigma_mps)
        ):
            return checks
        return checks.with_less_inflation(fraction, self.robot_radius_m, self.settings, cap_too=True)

    def _keep_previous_way(self, chosen: _Chosen, checks: LegChecks, speeds: np.ndarray, nominal_index: int) -> _Chosen:
        previous = cast(Choice, self._previous)  # called only when there is one
        if chosen.candidates is None:
            return chosen  # a free straight leg at nominal speed (the paper's first choice)
        if chosen.choice.way == previous.way:
            return chosen  # the previous way chosen again (the test below would find it among the candidates)
        # Why the way changed, for analysis (tests/planning/test_motion_noise.py counts it): the relaxed search helps only
        # where the previous way vanished with the inflation, not where the forecast itself moved.
        why = chosen.plan.extras
        if previous.way.same(chosen.candidates.ways).any():
            why["way_change"] = "cost"  # the previous way is still there: a fair switch on cost
            return chosen
        obstacles = checks.obstacles
        if not (np.any(obstacles.position_sigma_m) or np.any(obstacles.velocity_sigma_mps)):
            why["way_change"] = "gone"  # no inflation to relax: the search would be the same
            return chosen
        relaxed = checks.with_less_inflation(self.config.keep_previous_inflation, self.robot_radius_m, self.settings)
        kept = self._choose(relaxed, speeds, nominal_index, previous, only_way=previous.way)
        if kept is None:
            why["way_change"] = "gone_relaxed_too"
            return chosen
        if kept.plan.candidate_costs[kept.plan.chosen] < chosen.plan.candidate_costs[chosen.plan.chosen]:
            kept.plan.extras["kept_previous_way"] = True
            return kept
        why["way_change"] = "relaxed_costs_more"
        return chosen

    # -- step 5: the command -------------------------------------------------------------------------

    def _command(self, situation: Situation, plan: Plan) -> Command:
        # With a shield the chosen plan's command was made for its check already (a plan is complete, turn in
        # place marked, before it is checked): the same situation and plan, the same command.
        last = self._last_command
        if last is not None and last[0] is situation and last[1] is plan:
            return last[2]
        command = self.steer(situation.observation, plan.target, plan.speed_mps, self.config.heading_gain)
        if plan.extras.get("turn_in_place"):
            turn = command.turn_rate_radps if command.turn_rate_radps else self._turn_towards(situation, plan.target)
            command = Command(0.0, turn)
        self._last_command = (situation, plan, command)
        return command

    def _turn_towards(self, situation: Situation, target: ArrayLike) -> float:
        offset = np.asarray(target) - situation.position
        error = float(wrap_angle(math.atan2(offset[1], offset[0]) - situation.robot.heading_rad))
        return float(
            np.clip(self.config.heading_gain * error, -self.limits.max_turn_rate_radps, self.limits.max_turn_rate_radps)
        )


def _straight_plan(checks: LegChecks, speed: float) -> Plan:
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


def _straight_chosen(plan: Plan) -> _Chosen:
    return _Chosen(Choice(Way(STRAIGHT, 0, 0), int(round(plan.speed_mps * 1000))), plan, None)


def _cost_terms(
    breakdown: Callable[[int], dict[str, float]], order: np.ndarray, rank: int, total: np.ndarray
) -> dict[str, Any]:
    """Each critic's share of E for the chosen candidate and the cheapest other one (for tuning and views);
    ``breakdown(k)``: candidate k's terms by critic name, and "total"."""
    best = int(order[rank])
    other = int(order[1] if rank == 0 else order[0]) if len(order) > 1 else None
    runner_up = breakdown(other) if other is not None and math.isfinite(total[other]) else None
    return {"chosen": breakdown(best), "runner_up": runner_up}


def ViaPathConfig(**values: Any) -> Settings:
    """The viapath planner's options, validated, defaults filled in (``make_planner(..., config=...)``)."""
    return VIAPATH_OPTIONS.validate(values, where="viapath")


def grow_step(
    checks: LegChecks, roots: RootLegs, config: Settings, slow_checks: LegChecks | None = None
) -> Candidates | None:
    """The candidate tree of the cycle: in one compiled call on the compiled path with its whole-step kernels
    (the same candidates), else :func:`.candidates.grow`, the numpy reference."""
    store = checks.arithmetic.grow(checks, slow_checks or checks, roots, config)  # type: ignore[no-untyped-call]
    if store is not None:
        return _candidates_of(store, checks.subgoal)
    return grow(checks, roots, config, slow_checks)


def escape_step(
    checks: LegChecks,
    limits: MotionLimits,
    config: Settings,
    previous: Command | None = None,
    arithmetic: Arithmetic | None = None,
) -> Decision:
    """Stop or escape (:func:`.escape.stop_or_escape`): its standing check and scores in two compiled calls on the
    compiled path with its whole-step kernels (the same figures, bit for bit), else its numpy reference.
    ``arithmetic``: the planner's own, when the cycle's (``checks.arithmetic``) leaves the whole steps out for
    static geometry: the escape treats static rows as every other obstacle (the standing check spans the
    horizon for both, and keeps no braking envelope), so its compiled kernels serve those cycles too."""
    compiled = (arithmetic or checks.arithmetic).escape(checks, limits, config, escape_fan(limits, config), previous)
    return stop_or_escape(checks, limits, config, previous, compiled)


def precompile() -> bool:
    """Compile every planner kernel now if numba is there and the whole-step ones are not compiled yet
    (about 30 s of CPU once per machine, the choice kernel most of it: numba caches them on disk); True
    when they are ready. Two planning cycles run all of them with the planner's own argument types: one whose
    straight leg is blocked (goal_legs and grow inside the choice kernels), one closed in from four sides,
    where no candidate is free and standing is hit too (the escape's kernels)."""
    if not numba_available():
        return False
    if not whole_steps_compiled():
        planner = ViaPathPlanner(
            DesignatedPath([[0.0, 0.0], [6.0, 0.0]], half_width_m=1.0), nominal_speed_mps=0.2, compute="numba"
        )
        for people in warm_up_crowds():
            planner.reset()
            planner.plan(Observation(0.0, RobotState(np.zeros(2), 0.0, 0.2, 0.0, 0.25), people))
    return True


def warm_up_crowds() -> list[Obstacles]:
    """:func:`precompile`'s people: one walking at the robot along the path (the choice), four closing in
    on it from all sides (the escape; tests/planning/test_backends.py checks that both cycles get there)."""
    sides = np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])
    return [
        Obstacles(np.array([[2.0, 0.0]]), np.array([[-0.2, 0.0]]), np.array([0.3])),
        Obstacles(0.9 * sides, -0.3 * sides, np.full(4, 0.3)),
    ]
