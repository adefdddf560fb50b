"""Passive-safety shield between any planner and the base (docs/design.md §7).

Sources: passive safety, "if a contact happens, the robot is at rest" (Fraichard & Asama 2004,
inevitable collision states; Bouraine, Fraichard & Salhi 2012; Mitsch & Platzer, IJRR 2017, who also
define *passive friendly* safety); Nav2's collision monitor as the engineering anchor (it treats
obstacles as static points; here they move).

Definition. A command (v, ω) is **admissible** when the robot, driving it for one control period
``dt_s`` and then braking as hard as its limits allow (speed and turn rate both braked towards 0 at
``max_accel_mps2`` / ``max_turn_accel_radps2``), sweeps a disc that meets no person's **forecast
disc** before it is at rest. Forecast disc of person i at time t: centre ``c_i + v_i t``, radius
``r_robot + r_i + margin_i + k σ_p,i + k σ_v,i t + a_p t² / 2``. In ``passive-friendly`` mode a
command must also bring the robot to rest early enough that the person, braking at ``a_p`` from its
forecast velocity once the robot is at rest, stops before reaching it: the robot's rest disc must
miss the capsule swept by the person's forecast disc at the rest time T_s while it brakes,
centre ``c_i + v_i T_s`` to ``c_i + v_i T_s + v_i |v_i| / (2 a_p)``.

With ``towards_only`` (the default) a meeting counts only while the robot moves towards the person's
forecast centre (u · (c_i − p) > 0): the robot is never the one moving into a person, which is what
the at-fault metric counts, while a person catching up from behind may meet a robot that drives
away from them (otherwise every faster person from behind stops the robot, and it is then hit at
rest: the paper's "speed up to stay ahead" case). ``towards_only: false`` is docs/design.md §7 to the
letter: at rest at every contact.

**At rest** means speed 0 at the start of a control period and during it: the period in which the
discrete model first stands still counts as moving, at the speed it began with. A real drive ramps
its speed down within that period, and the at-fault metric reads the speed at the start of the
step in which a contact begins.

The motion model is the project's (``viapath.kinematics``): the drive reaches the commanded (v, ω)
through the acceleration limits once per control period and holds it along an exact arc for the
period, as the simulator and the planner's roll-outs do. The set of (v, ω) that one period can
reach is the **dynamic window**; a command outside it has the same effect as the window point it
is clipped to, so the shield samples the window (``samples`` per axis) and no command is missed.

Choices where the sources are silent:
* The swept-disc test is exact per sub-interval (a period split into pieces of at most ``substep_s``): relative motion of robot
  and forecast centre is a line there (robot arcs are replaced by chords, padded by
  ``4 τ · |v ω| h² / 8``, which bounds the arc's distance from its chord at fraction τ) and the forecast radius, convex in t, by its chord (above it by at most
  ``a_p h² / 8``); the disc test is then a quadratic inequality in time, solved exactly. The test
  can only err on the safe side, by those two pads.
* A person closer than the margin (+ k σ_p) but not touching gets that static part of its radius cut
  to its present gap: the robot may still move in ways that do not bring it nearer, instead of
  freezing whenever someone passes within 5 cm (and the disc never holds the robot at t = 0, which
  no command could change).
* A person already overlapping the robot disc (contact happening now): no command is admissible
  and the shield brakes as hard as it can. Driving away might end the contact sooner, but it would
  be the robot moving during a contact; at rest is the passive-safe answer.
* "Closest" is measured in the window's (v, ω) reached after one period, each axis divided by its
  limit (max speed, max turn rate); ties go to the slower command. With no admissible command the
  output is the hardest braking, Command(0, 0). In passive-friendly mode the fallback order is:
  friendly commands, then (if none is friendly) the planner's command if passively admissible, else
  the closest passively admissible one, else the hardest braking.
* "Towards" on a sub-interval is bounded, not sampled: u · (c − p) is at most its end values' mean
  plus half the interval times a bound on its rate (|v||ω||c − p| + |v|(|v_i| + |v|)).
* Position uncertainty k σ_p is added to the radius (constant in t) besides the velocity term.
* A person is skipped when it cannot come within reach of the robot before the longest braking
  ends (a bound: its distance minus its forecast reach exceeds the robot's longest sweep).

One implementation, compiled (:func:`viapath.jit.compiled`; plain Python with ``NUMBA_DISABLE_JIT=1``):
the braking sweep in :mod:`viapath.safety.sweep`, the test of K commands in :mod:`viapath.safety.verdicts`
and the window search in :mod:`viapath.safety.window`. This module holds the options, the results and the
filter's decisions around them. The independent brute forces in ``tests/safety`` check the claims.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from viapath import jit
from viapath.observation import Command, MotionLimits, Observation, Obstacles, RobotState
from viapath.path import DesignatedPath
from viapath.safety.options import check_options
from viapath.safety.sweep import Drive
from viapath.safety.verdicts import Corridor, Fields, Forecast, Statics, evaluate_fields
from viapath.safety.window import Found, search_fields

_EMPTY_POINTS, _EMPTY = np.zeros((0, 2)), np.zeros(0)
_NO_STATICS = tuple(Statics(_EMPTY_POINTS, _EMPTY))
_NO_CORRIDOR = tuple(Corridor(_EMPTY_POINTS, _EMPTY_POINTS, _EMPTY, _EMPTY))


@dataclass(frozen=True)
class ShieldConfig:
    """The shield's options; see :data:`viapath.safety.options.SHIELD_OPTIONS` for units and bounds."""

    enabled: bool = True
    mode: str = "passive"
    margin_m: float = 0.05
    person_accel_mps2: float = 1.0
    sigma_multiplier: float = 2.0
    samples: int = 11
    substep_s: float = 0.025
    towards_only: bool = True
    keep_in_corridor: bool = True

    def __post_init__(self) -> None:
        check_options({name: getattr(self, name) for name in self.__dataclass_fields__})

    @classmethod
    def from_options(cls, values: dict[str, Any] | None = None, where: str = "shield") -> ShieldConfig:
        return cls(**check_options(dict(values or {}), where))


@dataclass(frozen=True)
class ShieldResult:
    """What the shield did this cycle."""

    command: Command  # what goes to the base
    original: Command  # what the planner asked for
    intervened: bool  # the command was replaced
    reason: str  # why (or why not)
    admissible: bool  # the output is admissible (False only for the hardest braking with none admissible)
    friendly: bool | None = None  # passive-friendly mode: the output is also friendly
    person_id: int | None = None  # the person the planner's command would have met first
    meet_time_s: float | None = None  # when, from now
    candidates: int = 0
    admissible_candidates: int = 0

    def as_dict(self) -> dict[str, Any]:
        return {
            "intervened": self.intervened,
            "reason": self.reason,
            "admissible": self.admissible,
            "friendly": self.friendly,
            "original": (self.original.speed_mps, self.original.turn_rate_radps),
            "command": (self.command.speed_mps, self.command.turn_rate_radps),
            "person_id": self.person_id,
            "meet_time_s": self.meet_time_s,
            "candidates": self.candidates,
            "admissible_candidates": self.admissible_candidates,
        }


class Shield:
    """Keeps the planner's command if admissible, else the admissible one closest to it, else brakes."""

    def __init__(self, limits: MotionLimits | None = None, dt_s: float = 0.1, config: ShieldConfig | None = None):
        if not (math.isfinite(dt_s) and dt_s > 0):
            raise ValueError(f"shield: control period dt_s must be a finite number > 0, found {dt_s}")
        self.limits = limits or MotionLimits()
        self.dt_s = float(dt_s)
        self.config = config or ShieldConfig()
        # The drive and forecast records of the compiled test, and what they were made of.
        self._records: tuple[Any, ...] = (None, None, None, None, None)
        # The records of the last obstacles tested (the obstacles object, its people and its static discs).
        self._obstacle_records: tuple[Any, ...] = (None, None, None)
        # The corridor's record and the path it was made of.
        self._corridor_record: tuple[DesignatedPath | None, Fields] = (None, _NO_CORRIDOR)
        # Within one cycle of a shielded planner (:meth:`remembering`), the verdicts on single commands: the
        # planner tests its chosen command against this observation and the filter then tests the same one.
        self._verdicts: dict[Any, Any] | None = None
        # The designated path whose corridor the robot must stay in (set by its owner each cycle; None: no
        # corridor, e.g. no path yet). Only read when ``config.keep_in_corridor``.
        self.corridor: DesignatedPath | None = None

    # -- the test --------------------------------------------------------------------------------

    def evaluate(self, observation: Observation, commands: np.ndarray) -> dict[str, np.ndarray]:
        """For each command (K, 2): ``admissible``, ``friendly``, ``meet_time_s`` (inf: never), ``person``
        (row of the first person met among the finite people, -1 none), ``static_meet_time_s``,
        ``corridor_exit_time_s`` (inf: never) and ``achieved`` (v, ω) of the first period. A person already
        touching the robot makes every command inadmissible (``contact`` is True)."""
        verdicts = self._verdicts
        if verdicts is not None and np.shape(commands) == (1, 2):
            key = (id(observation), np.asarray(commands, dtype=np.float64).tobytes())  # bit for bit (-0.0 too)
            known = verdicts.get(key)
            if known is not None and known[0] is observation:
                return known[1]
            out = self._evaluate(observation, commands)
            verdicts[key] = (observation, out)
            return out
        return self._evaluate(observation, commands)

    @contextlib.contextmanager
    def remembering(self) -> Iterator[None]:
        """Within this block (one planning cycle: the observation does not change) a single command is
        tested once against one observation, and its verdict reused (evaluate is a pure function of them).
        The verdicts are read, never changed, by their users."""
        self._verdicts = {}
        try:
            yield
        finally:
            self._verdicts = None
            self._obstacle_records = (None, None, None)

    def _evaluate(self, observation: Observation, commands: np.ndarray) -> dict[str, np.ndarray]:
        drive, forecast = self._drive_and_forecast()
        people, statics = self._people_and_statics(observation.obstacles)
        commands = _c(np.reshape(commands, (-1, 2)))
        # The fields of a Verdicts record, in its order.
        achieved, admissible, friendly, meet, person, contact, static_meet, corridor_exit = evaluate_fields(
            _robot(observation.robot), drive, forecast, commands, people, statics, self._corridor()
        )
        return {
            "achieved": achieved,
            "admissible": admissible,
            "friendly": friendly,
            "meet_time_s": meet,
            "person": person,
            "contact": np.full(1, contact),
            "static_meet_time_s": static_meet,
            "corridor_exit_time_s": corridor_exit,
        }

    def _drive_and_forecast(self) -> tuple[Fields, Fields]:
        """The compiled test's constants, made again only when the limits, period or options are replaced."""
        limits, dt_s, config = self.limits, self.dt_s, self.config
        records = self._records
        if records[0] is limits and records[1] == dt_s and records[2] is config:
            return records[3], records[4]
        drive = Drive(
            float(limits.max_speed_mps),
            float(limits.max_accel_mps2),
            float(limits.max_turn_rate_radps),
            float(limits.max_turn_accel_radps2),
            dt_s,
            max(1, math.ceil(dt_s / config.substep_s - 1e-9)),
        )
        forecast = Forecast(
            float(config.margin_m),
            float(config.sigma_multiplier),
            float(config.person_accel_mps2),
            config.mode == "passive-friendly",
            bool(config.towards_only),
        )
        self._records = (limits, dt_s, config, tuple(drive), tuple(forecast))
        return self._records[3], self._records[4]

    def _people_and_statics(self, obstacles: Obstacles) -> tuple[Fields, Fields]:
        """:func:`_people_and_statics`, made once per obstacles object within one cycle (:meth:`remembering`:
        a cycle tests its observation more than once, the planner's command, the filter's, the window)."""
        if self._verdicts is None:
            return _people_and_statics(obstacles)
        known = self._obstacle_records
        if known[0] is not obstacles:
            known = self._obstacle_records = (obstacles, *_people_and_statics(obstacles))
        return known[1], known[2]

    def _corridor(self) -> Fields:
        """The corridor the sweeps must keep to (an inactive record when there is none to keep to)."""
        path = self.corridor
        if path is None or not self.config.keep_in_corridor:
            return _NO_CORRIDOR
        known, record = self._corridor_record
        if known is not path:
            record = tuple(
                Corridor(
                    _c(path.segment_starts),
                    _c(path.segment_directions),
                    _c(path.segment_lengths_m),
                    _c(path.half_widths_m),
                )
            )
            self._corridor_record = (path, record)
        return record

    # -- the filter ------------------------------------------------------------------------------

    def filter(self, observation: Observation, command: Command) -> ShieldResult:
        """What goes to the base instead of ``command`` (the planner's), and why."""
        config = self.config
        original = command
        if not config.enabled:
            return ShieldResult(command, original, False, "shield disabled", False)
        if not (math.isfinite(command.speed_mps) and math.isfinite(command.turn_rate_radps)):
            command = Command.stop()
        limits = self.limits
        friendly_mode = config.mode == "passive-friendly"
        # Within the limits (the drive would clip it the same way): the output never exceeds them.
        command = Command(
            min(max(float(command.speed_mps), 0.0), limits.max_speed_mps),
            min(max(float(command.turn_rate_radps), -limits.max_turn_rate_radps), limits.max_turn_rate_radps),
        )
        # Most cycles the planner's command passes: test it alone first, the window only when it fails.
        own = self.evaluate(observation, np.array([[command.speed_mps, command.turn_rate_radps]]))
        own_ok, own_friendly = bool(own["admissible"][0]), bool(own["friendly"][0])
        if own_friendly if friendly_mode else own_ok:
            friendly = True if friendly_mode else None
            return ShieldResult(command, original, False, "admissible", True, friendly, None, None, 1, 1)
        person_id, meet, why = self._first_meeting(observation, own)
        if bool(own["contact"][0]):
            stop = Command.stop()
            return ShieldResult(
                stop,
                original,
                not _same(original, stop),
                f"contact already happening with person {person_id}: at rest",
                False,
                False if friendly_mode else None,
                person_id=person_id,
                meet_time_s=0.0,
                candidates=1,
            )
        return self._replace(observation, command, original, own_ok, person_id, meet, why)

    def _first_meeting(
        self, observation: Observation, own: dict[str, np.ndarray]
    ) -> tuple[int | None, float | None, str]:
        """From the verdict on the planner's own command: the id of the person it meets first (None: static
        geometry or nobody), when (s; None: never) and why it fails, in words."""
        ids = observation.obstacles.people().finite().ids
        first = int(own["person"][0])
        person_id = int(ids[first]) if first >= 0 else None
        meet = float(own["meet_time_s"][0]) if math.isfinite(own["meet_time_s"][0]) else None
        static_meet = float(own["static_meet_time_s"][0])
        if math.isfinite(static_meet) and (meet is None or static_meet < meet):
            person_id, meet = None, static_meet
        corridor_exit = float(own["corridor_exit_time_s"][0])
        leaves_first = math.isfinite(corridor_exit) and (meet is None or corridor_exit < meet)
        why = (
            f"would leave the corridor {corridor_exit:.2f} s ahead before at rest"
            if leaves_first
            else f"would meet person {person_id} {meet:.2f} s ahead before at rest"
            if person_id is not None
            else f"would touch static geometry {meet:.2f} s ahead before at rest"
            if meet is not None
            else "the person would have no room to stop"
        )
        return person_id, meet, why

    def _replace(
        self,
        observation: Observation,
        command: Command,
        original: Command,
        own_ok: bool,
        person_id: int | None,
        meet: float | None,
        why: str,
    ) -> ShieldResult:
        """The planner's (clipped) ``command`` failed: the closest wanted command of the window, else (in
        passive-friendly mode) the command itself or the closest admissible one, else the hardest braking."""
        friendly_mode = self.config.mode == "passive-friendly"
        found = self._search(observation, command)
        if found.pick >= 0:
            text = (
                f"not friendly ({why}): closest friendly command"
                if friendly_mode
                else f"{why}: closest admissible command"
            )
            friendly = True if friendly_mode else None
            picked = _as_command(found.reached, found.pick)
            return ShieldResult(
                picked, original, True, text, True, friendly, person_id, meet, found.tested + 1, found.passing
            )
        common: dict[str, Any] = dict(
            person_id=person_id,
            meet_time_s=meet,
            candidates=found.tested + 1,
            admissible_candidates=found.passing + int(own_ok),
        )
        if friendly_mode and own_ok:
            return ShieldResult(
                command, original, False, "admissible (no friendly command exists)", True, False, **common
            )
        if found.passive_pick >= 0:
            picked = _as_command(found.reached, found.passive_pick)
            text = f"{why}: closest admissible command (no friendly one)"
            return ShieldResult(picked, original, True, text, True, False, **common)
        stop = Command.stop()
        text = f"{why}: none admissible, hardest braking"
        return ShieldResult(
            stop, original, not _same(original, stop), text, False, False if friendly_mode else None, **common
        )

    def _search(self, observation: Observation, command: Command) -> Found:
        """The window search (:func:`viapath.safety.window.search`) for the planner's failed ``command``."""
        drive, forecast = self._drive_and_forecast()
        people, statics = self._people_and_statics(observation.obstacles)
        reached, pick, passive_pick, tested, passing = search_fields(
            _robot(observation.robot),
            drive,
            forecast,
            (float(command.speed_mps), float(command.turn_rate_radps)),
            int(self.config.samples),
            people,
            statics,
            self._corridor(),
        )
        # Plain ints (in plain Python the counts and rows are numpy integers).
        return Found(reached, int(pick), int(passive_pick), int(tested), int(passing))


def _robot(robot: RobotState) -> Fields:
    """The fields of the compiled test's :class:`viapath.safety.sweep.Robot`, in its order."""
    position = robot.position
    return (
        float(position[0]),
        float(position[1]),
        float(robot.heading_rad),
        float(robot.speed_mps),
        float(robot.turn_rate_radps),
        float(robot.radius_m),
    )


def _people_and_statics(obstacles: Obstacles) -> tuple[Fields, Fields]:
    """The people (every row but static geometry; the compiled test leaves out those with a field not finite)
    and the static discs, as the compiled test's records."""
    people = obstacles.people()
    record = (
        _c(people.positions),
        _c(people.velocities),
        _c(people.radii_m),
        _c(people.position_sigma_m),
        _c(people.velocity_sigma_mps),
    )  # People's fields
    if obstacles.static_mask is None:
        return record, _NO_STATICS
    statics = obstacles.statics()
    return record, (_c(statics.positions), _c(statics.radii_m))  # Statics' fields


def _c(array: ArrayLike) -> np.ndarray:
    """A C-contiguous float64 array (the array type the compiled test is compiled for; a read-only one compiles
    once more)."""
    return np.ascontiguousarray(array, dtype=np.float64)


def _as_command(reached: np.ndarray, index: int) -> Command:
    if index == 1:  # the hardest braking itself
        return Command.stop()
    return Command(float(reached[index, 0]), float(reached[index, 1]))


def precompile() -> bool:
    """Compile the shield (or load it from the on-disk cache) now: a cycle whose planner's command fails,
    with a person, static geometry and a corridor, runs every compiled step once. True when compiled."""
    shield = Shield()
    shield.corridor = DesignatedPath([[-5.0, 0.0], [5.0, 0.0], [5.0, 5.0]], half_width_m=1.0)
    obstacles = Obstacles(
        np.array([[1.0, 0.0], [0.0, 0.8]]),
        np.array([[-0.5, 0.0], [0.0, 0.0]]),
        np.array([0.25, 0.1]),
        static_mask=np.array([False, True]),
    )
    observation = Observation(0.0, RobotState(np.zeros(2), 0.0, 0.3, 0.0, 0.25), obstacles)
    shield.filter(observation, Command(0.5, 0.0))
    return jit.enabled()


def _same(a: Command, b: Command) -> bool:
    return a.speed_mps == b.speed_mps and a.turn_rate_radps == b.turn_rate_radps
