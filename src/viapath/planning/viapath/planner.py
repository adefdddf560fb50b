"""The paper's planner, as its procedure: situation → candidates → costs → the first candidate the
robot can follow → command; with no free candidate, stop or escape.

Source: Yamada, Sa, Ohya, §3 (procedure steps 1-5, Eq. 1), after Tsubouchi et al.; docs/design.md §2. Each
step is a module of this package, named after it:

1. situation (:mod:`.checks`): the subgoal, the people with their capped uncertainty cones, the corridor;
2. candidates (:mod:`.candidates`, grown by :mod:`.tree`): for every speed of the set
   (:meth:`ViaPathPlanner.speed_set`), the straight leg, via points chained through further obstacles, slow/wait,
   the way back through the path's corners (paper step 1: a free straight leg at the nominal speed is the plan
   at once);
3. costs (:mod:`.critics`): Eq. 1 as critics, plus side preference and hysteresis;
4. follow (:mod:`.follow`): the cheapest candidate whose first leg the robot can follow within its
   motion limits and, with a shield behind the planner (docs/design.md §7), whose command the shield admits
   (via points then also keep the robot's braking envelope from people);
5. command: steer for the plan's target at the plan's speed (turning on the spot first if needed);
6. escape (:mod:`.escape`): stop if standing is safe, else the drive command that stays clear longest.

Steps 1-4 run as one compiled call in every cycle, with static geometry in view or not (:mod:`.choice`). The
extensions beyond the paper are named steps beside the recipe, each a module: the way back (:mod:`.way_back`), the
outrun hold (:mod:`.outrun`), the kept way (:mod:`.kept_way`), static geometry near the corridor and the
closed way (:mod:`.blocked`), after the decision stepping aside (:mod:`.step_aside`) and holding short of a stream
(:mod:`.stream_band`); the creep is a slow candidate (:mod:`.candidates`).

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
* **Static obstacles** (docs/design.md §10; the paper draws its path boundary round static things and plans for
  moving ones only). A static obstacle is a vertical prism in x-y-t: the guarded entry hands the planner
  the observation's static layer as discs of velocity 0 sampled along its segments (within a few mm of
  the segments' capsules, :mod:`viapath.static`), so the legs are checked against it exactly as against
  people (a cylinder of velocity 0 is the prism), and the same via-point code makes its avoiding lines
  (v_i = 0: t* = |w|/v). What is ours: (1) via points go round a whole **shape**, not the one disc a leg
  met first: a pair (node, static disc) becomes the two discs of that disc's shape that reach furthest
  left and right as seen from the node (the tangents to the shape's inflated outline,
  :func:`.shapes.extremes`), and the root branches once per shape (:func:`.shapes.one_per_shape`); a node hugging
  a shape slides along it instead of creeping round its nearest disc (:func:`.shapes.slide`);
  (2) static legs are checked to their end, past the horizon (a leg into a wall is not made free by
  driving it slowly), and without the shield's braking envelope, which is for where people may walk;
  (3) static discs farther outside the corridor than their reach are left out of the cycle (no
  candidate can meet them); (4) with no free candidate, the corridor's free space flooded from the robot
  (:mod:`.flood`) tells a way round from a closed way (:mod:`.blocked`): if the subgoal is reachable but the
  tree finds nothing even without the people, the tree runs again towards a point of the flood's way there;
  if it is not reachable (standing being safe), the robot drives to the farthest point along the path the
  flood reaches, ``blocked_gap_m`` short of touching anything, at a speed from which it stops there, and
  waits with status ``blocked``; every cycle looks again, so it goes on when the door opens. The candidate
  tree does (1) and (2) in the compiled choice, as it grows (:mod:`.shapes`); the escape treats static discs
  as any obstacle.
* The way back (``return_lookahead_m``, 0.5 m by default; 0 in the preset ``paper``): off the path
  line, the paper's step 1 is tried first towards the path point that far ahead instead of the
  subgoal. The paper heads for the subgoal; when that is metres away the robot drifts back to the path
  on a shallow line after a pass, and that drift was most of the extra deviation of a passing robot
  (docs/howto/tune-weights.md §6).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, cast

import numpy as np
from numpy.typing import ArrayLike

from viapath.geometry import wrap_angle
from viapath.observation import Command, Observation, Obstacles, RobotState
from viapath.options import Settings
from viapath.path import DesignatedPath
from viapath.planning.base import Decision, Plan, Planner, Situation
from viapath.planning.viapath.blocked import blocked, detour, near_corridor
from viapath.planning.viapath.candidates import Candidates, Choice, Way
from viapath.planning.viapath.checks import LegChecks
from viapath.planning.viapath.choice import choose_compiled, tree_is_empty
from viapath.planning.viapath.critics import Context, Critic, critics_for
from viapath.planning.viapath.escape import stop_or_escape
from viapath.planning.viapath.follow import can_follow
from viapath.planning.viapath.kept_way import keep_previous_way
from viapath.planning.viapath.options import VIAPATH_OPTIONS
from viapath.planning.viapath.outrun import outrun, outrun_held
from viapath.planning.viapath.plans import Chosen, straight_chosen, straight_plan
from viapath.planning.viapath.step_aside import step_aside
from viapath.planning.viapath.stream_band import StreamBand, hold_short
from viapath.planning.viapath.way_back import way_back


class ViaPathPlanner(Planner, name="viapath"):
    """Yamada-Sa-Ohya planner: follows the designated path, avoids by changing speed and direction."""

    options = VIAPATH_OPTIONS

    def __init__(self, path: DesignatedPath, *, config: Mapping[str, Any] | None = None, **kwargs: Any) -> None:
        if config is not None:  # a mapping of options (e.g. ViaPathConfig(...)), before any keyword
            kwargs["options"] = {**dict(config), **dict(kwargs.get("options") or {})}
        super().__init__(path, **kwargs)
        self.config = self.settings
        self.critics = critics_for(self.config)
        self._previous: Choice | None = None
        self._previous_escape: Command | None = None  # last cycle's command, if it escaped
        self._situation: Situation | None = None  # this cycle's, for the shield check of candidates
        self._last_command: tuple[Any, ...] | None = None  # (situation, plan, command) of the last command made
        self._straight_speed: float | None = None  # last cycle's speed if its plan was the straight leg
        self._outrun_seen_s = -math.inf  # when someone from behind last blocked the nominal leg (outrun)
        self._checks: LegChecks | None = None  # this cycle's (for the step aside)
        self._step_aside_target: np.ndarray | None = None  # last cycle's, if it stepped aside
        self._stream_band = StreamBand()  # people's recent tracks, for holding short of a stream

    def reset(self) -> None:
        super().reset()
        self._previous = None
        self._previous_escape = None
        self._last_command = None
        self._straight_speed = None
        self._outrun_seen_s = -math.inf
        self._step_aside_target = None
        self._stream_band.reset()

    # -- the recipe ----------------------------------------------------------------------------------

    def decide(self, situation: Situation) -> Decision:
        decision = self._decide(situation)
        if self.config.step_aside_s > 0 and self._checks is not None:
            # A wait plan's standing was checked with less uncertainty inflation: so is staying on it.
            checks = self._slow_checks(self._checks) if decision.plan.status == "wait" else self._checks
            aside = step_aside(self, checks, decision, self._step_aside_target)
            self._step_aside_target = None if aside is None else aside.plan.target
            if aside is not None:
                if decision.plan.status == "escape":
                    self._previous_escape = aside.command  # the command sent, for a calm escape next cycle
                decision = aside
        if self.config.stream_band_s > 0 and self._checks is not None:
            band = self._stream_band
            band.observe(situation.observation.time_s, self._checks, self.config.stream_band_s)
            decision = hold_short(self, self._checks, decision, band) or decision
        plan = decision.plan
        self._straight_speed = plan.speed_mps if plan.status == "straight" else None
        return decision

    def _decide(self, situation: Situation) -> Decision:
        if situation.obstacles.static_mask is not None:
            situation = near_corridor(self, situation)
        self._situation = situation
        checks = LegChecks.of(
            situation,
            self.config,
            self.subgoals,
            self.subgoal_policy,
            self.robot_radius_m,
        )
        self._checks = checks
        if self.shield is not None and self.shield.config.enabled:
            # Set on the checks just built (dataclasses.replace would copy every field again, every cycle).
            checks.envelope_accel_mps2 = self.shield.config.person_accel_mps2
            checks.envelope_period_s = self.shield.dt_s
            checks.max_accel_mps2 = self.limits.max_accel_mps2
        speeds, nominal_index = self.speed_set(situation.robot.speed_mps)
        chosen = self._choose(checks, speeds, nominal_index, self._previous)
        if chosen is None and checks.obstacles.static_mask is not None:
            chosen = detour(self, checks, speeds, nominal_index)
            if chosen is not None:  # a way round static geometry the tree alone did not find (:mod:`.blocked`)
                self._previous = self._previous_escape = None
                return Decision(self._command(situation, chosen.plan), chosen.plan)
        if chosen is None:
            self._previous = None
            decision = stop_or_escape(checks, self.limits, self.config, self._previous_escape)
            self._previous_escape = decision.command if decision.plan.status == "escape" else None
            if decision.plan.status == "stop" and checks.obstacles.static_mask is not None:
                return blocked(self, situation, checks, float(speeds[nominal_index])) or decision
            return decision
        self._previous_escape = None
        if self.config.keep_previous_way and self._previous is not None:
            chosen = keep_previous_way(self, chosen, checks, speeds, nominal_index)
        self._previous = chosen.choice
        return Decision(self._command(situation, chosen.plan), chosen.plan)

    def speed_set(self, current_speed_mps: float) -> tuple[np.ndarray, int]:
        """The configured speeds, the current speed and the nominal speed (mm/s resolution, within
        the limit), sorted; and where the nominal speed is in it. The same set is the same array (read only
        by the planner's steps: do not change it)."""
        top = self.limits.max_speed_mps
        current = round(min(current_speed_mps, top), 3) if current_speed_mps > 0.02 else None
        # The same few sets come back cycle after cycle (one per current speed in mm/s): kept while the
        # options, limits and nominal speed are the same objects.
        config, limits, nominal_speed = self.config, self.limits, self.nominal_speed_mps
        cached = self.__dict__.get("_speed_sets")
        if cached is None or cached[0] is not config or cached[1] is not limits or cached[2] is not nominal_speed:
            cached = self.__dict__["_speed_sets"] = (config, limits, nominal_speed, {})
        known: dict[float | None, tuple[np.ndarray, int]] = cached[3]
        found = known.get(current)
        if found is None:
            nominal = self.nominal_in_speed_set_mps()
            speeds = {round(min(v, top), 3) for v in self.config.speeds} | {nominal}
            if current is not None:
                speeds.add(current)
            ordered = sorted(speeds)
            if len(known) >= 4096:  # a long run through many current speeds: start again
                known.clear()
            found = known[current] = (np.array(ordered), ordered.index(nominal))
        return found

    def nominal_in_speed_set_mps(self) -> float:
        return round(min(self.nominal_speed_mps, self.limits.max_speed_mps), 3)

    def _choose(
        self,
        checks: LegChecks,
        speeds: np.ndarray,
        nominal_index: int,
        previous: Choice | None,
        only_way: Way | None = None,
    ) -> Chosen | None:
        """Candidates → costs → the cheapest the robot can follow; None when none is free.
        With ``only_way``, only candidates going that way round are considered. Staying ahead of someone
        catching up from behind, the straight leg's speed is the slowest that holds (:mod:`.outrun`)."""
        staying_ahead = only_way is None and self.config.outrun_hold_s > 0
        if staying_ahead and self._straight_speed is not None:
            held = outrun_held(self, checks, speeds, nominal_index)
            if held is not None:
                return held
        chosen = self._cheapest(checks, speeds, nominal_index, previous, only_way)
        if staying_ahead and chosen is not None:
            return outrun(self, checks, speeds, nominal_index, chosen) or chosen
        return chosen

    def _cheapest(
        self,
        checks: LegChecks,
        speeds: np.ndarray,
        nominal_index: int,
        previous: Choice | None,
        only_way: Way | None = None,
    ) -> Chosen | None:
        """Paper steps 1-4 (:meth:`_choose` without the speed of outrunning): the way back, else the compiled
        choice (:mod:`.choice`)."""
        if only_way is None and self.config.return_lookahead_m > 0:
            back = way_back(self, checks, float(speeds[nominal_index]))
            if back is not None:
                return back
        return choose_compiled(self, checks, speeds, nominal_index, previous, only_way)

    def _straight(self, checks: LegChecks, speed: float) -> Chosen | None:
        """The straight leg to the subgoal at ``speed`` as the plan, if the robot can turn onto it in time
        (and the shield admits its command); its freedom is the caller's to check."""
        plan = straight_plan(checks, speed)
        if can_follow(plan, checks, self.limits, self.config) and self._inside_shield(plan):
            return straight_chosen(plan)
        return None

    # -- step 4 with a shield behind the planner ------------------------------------------------------

    def _inside_shield(self, plan: Plan) -> bool:
        """With a shield (docs/design.md §7) behind the planner, a candidate whose command the shield would refuse
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

    def _slow_checks(self, checks: LegChecks) -> LegChecks:
        """``checks`` with ``slow_leg_inflation`` of the uncertainty inflation (slow/wait legs and standing), made
        once per checks: the choice, a second choice keeping last cycle's way and the step aside after a wait all
        ask."""
        kept = checks.__dict__.get("_slow_checks")  # False: the checks themselves (no reference from them to them)
        if kept is not None:
            return checks if kept is False else kept
        fraction = self.config.slow_leg_inflation
        # (np.count_nonzero: what .any() answers, NaN counting as not zero, in a fifth of the time of .any() or of
        # np.logical_or.reduce on a cycle's few sigmas)
        any_nonzero = np.count_nonzero
        if fraction >= 1.0 or not (
            any_nonzero(checks.obstacles.position_sigma_m) or any_nonzero(checks.obstacles.velocity_sigma_mps)
        ):
            checks.__dict__["_slow_checks"] = False
            return checks
        slow = checks.__dict__["_slow_checks"] = checks.with_less_inflation(
            fraction, self.robot_radius_m, self.settings, cap_too=True
        )
        return slow

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


def ViaPathConfig(**values: Any) -> Settings:
    """The viapath planner's options, validated, defaults filled in (``make_planner(..., config=...)``)."""
    return VIAPATH_OPTIONS.validate(values, where="viapath")


def precompile() -> bool:
    """Compile every compiled step of the planner now (or load them from the on-disk cache: about 30 s of CPU once per
    machine, the compiled choice most of it). Two planning cycles run all of them with the planner's own argument
    types: one whose straight leg is blocked (the compiled choice with its goal legs and tree), one closed in from
    four sides, where no candidate is free and standing is hit too (the compiled escape), the second again from rest
    (the step aside's roll-outs). Then the two calls no cycle of theirs makes: the candidate tree alone (the way
    round static geometry asks whether static geometry closes the tree, :func:`.choice.tree_is_empty`) and the
    choice in two halves that a critic beyond the paper's takes (:class:`_Unscored`). True when done."""
    planner = ViaPathPlanner(DesignatedPath([[0.0, 0.0], [6.0, 0.0]], half_width_m=1.0), nominal_speed_mps=0.2)
    robot = RobotState(np.zeros(2), 0.0, 0.2, 0.0, 0.25)
    standing = RobotState(np.zeros(2), 0.0, 0.0, 0.0, 0.25)
    crowds = warm_up_crowds()
    for state, people in ((robot, crowds[0]), (robot, crowds[1]), (standing, crowds[1])):
        planner.reset()
        planner.plan(Observation(0.0, state, people))
    checks = planner._checks
    assert checks is not None  # set by every cycle
    tree_is_empty(planner, checks, *planner.speed_set(robot.speed_mps))
    planner.critics = (*planner.critics, _Unscored())
    planner.reset()
    planner.plan(Observation(0.0, robot, crowds[0]))
    return True


class _Unscored(Critic):
    """A critic beyond the paper's that adds nothing: :func:`precompile`'s way into the choice in two halves."""

    name = "unscored"

    def score(self, candidates: Candidates, context: Context) -> np.ndarray:
        return np.zeros(len(candidates))


def warm_up_crowds() -> list[Obstacles]:
    """:func:`precompile`'s people: one walking at the robot along the path (the choice), four closing in
    on it from all sides (the escape; tests/planning/test_compiled_choice.py checks that both cycles get there)."""
    sides = np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])
    return [
        Obstacles(np.array([[2.0, 0.0]]), np.array([[-0.2, 0.0]]), np.array([0.3])),
        Obstacles(0.9 * sides, -0.3 * sides, np.full(4, 0.3)),
    ]
