"""Passive-safety shield between any planner and the base (DESIGN §7).

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
rest: the paper's "speed up to stay ahead" case). ``towards_only: false`` is DESIGN §7 to the
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

Speed (docs/speed.md): the numpy code here is the reference; option ``compute`` (``auto``
| ``numpy`` | ``numba``, as the planner's, env ``VIAPATH_PLANNER_BACKEND`` overriding ``auto``) may
run :meth:`Shield.evaluate` and the window search of :meth:`Shield.filter` on
:mod:`viapath.compiled.shield` instead, the same arithmetic compiled (extra ``fast``), with the same
verdicts (tests/safety/test_shield_backends.py); ``ShieldResult.backend`` says which ran. The
compiled shield takes about 12 s to compile, once per machine; ``auto`` uses it only once it is
compiled (:func:`precompile`, which ``viapath bench`` and the ROS 2 node call before they start),
so that a first short ``viapath run`` does not wait for it (docs/speed.md). ``numba``, or the
environment variable set to ``numba``, compiles it on first use.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from viapath.compiled import explicit, numba_available, ready, require
from viapath.compiled import resolve as resolve_backend
from viapath.observation import Command, MotionLimits, Observation, Obstacles, RobotState
from viapath.path import DesignatedPath
from viapath.safety.options import check_options

_STRAIGHT = 1e-9
_CHUNK = 24  # candidates tested at once when the planner's command fails
_NEVER = np.full(1, np.inf)
# Outside the corridor by more than this counts as leaving it (the benchmark's time-outside metric: 1e-6 m).
_CORRIDOR_TOLERANCE_M = 1e-6


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
    compute: str = "auto"

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
    backend: str = "numpy"  # which arithmetic ran the test (numpy reference or the compiled kernels)

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
            "backend": self.backend,
        }


@dataclass
class Sweep:
    """Braking roll-outs of K commands: positions at the sub-interval ends and when each is at rest."""

    times_s: np.ndarray  # (T,) sub-interval ends, t=0 first
    positions: np.ndarray  # (K, T, 2)
    moving: np.ndarray  # (K, T-1) the robot moves during sub-interval n
    sagitta_m: np.ndarray  # (K, T-1) arc-vs-chord pad
    rest_time_s: np.ndarray  # (K,)
    rest_position: np.ndarray  # (K, 2)
    reach_m: np.ndarray  # (K,) path length until rest
    achieved: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))  # (K, 2) (v, ω) of the first period
    headings: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))  # (K, T) at the sub-interval ends
    speeds: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))  # (K, T-1) during each sub-interval
    turns: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))  # (K, T-1)


def achieved_first_period(
    commands: np.ndarray, speed_mps: float, turn_rate_radps: float, limits: MotionLimits, dt_s: float
) -> np.ndarray:
    """(v, ω) the drive reaches in one period for each command (K, 2): as :func:`viapath.kinematics.limit_command`."""
    commands = np.asarray(commands, dtype=float).reshape(-1, 2)
    v_cmd = np.clip(np.where(np.isfinite(commands[:, 0]), commands[:, 0], 0.0), 0.0, limits.max_speed_mps)
    w_cmd = np.clip(
        np.where(np.isfinite(commands[:, 1]), commands[:, 1], 0.0),
        -limits.max_turn_rate_radps,
        limits.max_turn_rate_radps,
    )
    bad = ~(np.isfinite(commands).all(axis=1))
    v_cmd[bad], w_cmd[bad] = 0.0, 0.0
    dv, dw = limits.max_accel_mps2 * dt_s, limits.max_turn_accel_radps2 * dt_s
    return np.stack(
        [speed_mps + np.clip(v_cmd - speed_mps, -dv, dv), turn_rate_radps + np.clip(w_cmd - turn_rate_radps, -dw, dw)],
        axis=1,
    )


def braking_sweep(
    position: np.ndarray,
    heading_rad: float,
    achieved: np.ndarray,
    limits: MotionLimits,
    dt_s: float,
    substeps: int,
    speed_now_mps: float = 0.0,
) -> Sweep:
    """One period at each achieved (v, ω), then the hardest braking, until the robot is at rest: its
    speed is 0 at the start of a period and during it (a drive ramps down within the period, and the
    at-fault metric reads the speed at the start of the step), so the period in which the discrete
    model first stands still still counts as moving (at the speed it had at its start)."""
    achieved = np.asarray(achieved, dtype=float).reshape(-1, 2)
    k = len(achieved)
    dv, dw = limits.max_accel_mps2 * dt_s, limits.max_turn_accel_radps2 * dt_s
    speeds, turns = [achieved[:, 0].copy()], [achieved[:, 1].copy()]
    # The drive's own recurrence (as kinematics.limit_command with a stop command), until all are at rest.
    limit = 10_000
    while np.any(speeds[-1] != 0.0) and len(speeds) < limit:
        s, w = speeds[-1], turns[-1]
        speeds.append(s + np.clip(-s, -dv, dv))
        turns.append(w + np.clip(-w, -dw, dw))
    speed = np.stack(speeds, axis=1)  # (K, J): the last step has speed 0 for every command
    turn = np.stack(turns, axis=1)
    previous = np.concatenate([np.full((k, 1), float(speed_now_mps)), speed[:, :-1]], axis=1)
    if not np.any(previous[:, -1] != 0.0) and speed.shape[1] > 1:
        speed, turn, previous = speed[:, :-1], turn[:, :-1], previous[:, :-1]  # nobody needs the rest step
    j = speed.shape[1]
    h = dt_s / substeps
    tau = h * np.arange(1, substeps + 1)  # (M,) sub-times inside a step
    heading_start = (
        float(heading_rad) + np.concatenate([np.zeros((k, 1)), np.cumsum(turn * dt_s, axis=1)], axis=1)[:, :j]
    )
    straight = np.abs(turn) < _STRAIGHT
    safe_turn = np.where(straight, 1.0, turn)
    h0 = heading_start[..., None]  # (K, J, 1)
    h1 = h0 + turn[..., None] * tau  # (K, J, M)
    s3, w3 = speed[..., None], safe_turn[..., None]
    dx = np.where(straight[..., None], s3 * tau * np.cos(h0), s3 / w3 * (np.sin(h1) - np.sin(h0)))
    dy = np.where(straight[..., None], s3 * tau * np.sin(h0), -s3 / w3 * (np.cos(h1) - np.cos(h0)))
    step_dx, step_dy = dx[..., -1], dy[..., -1]  # (K, J) whole-step displacement
    start_x = float(position[0]) + np.concatenate([np.zeros((k, 1)), np.cumsum(step_dx, axis=1)], axis=1)[:, :j]
    start_y = float(position[1]) + np.concatenate([np.zeros((k, 1)), np.cumsum(step_dy, axis=1)], axis=1)[:, :j]
    positions = np.empty((k, j * substeps + 1, 2))
    positions[:, 0] = position
    positions[:, 1:, 0] = (start_x[..., None] + dx).reshape(k, -1)
    positions[:, 1:, 1] = (start_y[..., None] + dy).reshape(k, -1)
    moving_steps = (speed != 0.0) | (previous != 0.0)
    moving = np.repeat(moving_steps, substeps, axis=1)
    effective = np.maximum(np.abs(speed), np.abs(previous))  # for "towards": the speed it may still have
    sagitta = np.repeat(np.abs(speed * turn) * h * h / 8.0, substeps, axis=1)
    steps_moving = moving_steps.sum(axis=1)
    rest_index = steps_moving * substeps
    return Sweep(
        times_s=h * np.arange(j * substeps + 1),
        positions=positions,
        moving=moving,
        sagitta_m=sagitta,
        rest_time_s=steps_moving * dt_s,
        rest_position=positions[np.arange(k), rest_index],
        reach_m=np.sum(np.abs(speed), axis=1) * dt_s,
        achieved=achieved,
        headings=np.concatenate([np.full((k, 1), float(heading_rad)), h1.reshape(k, -1)], axis=1),
        speeds=np.repeat(effective, substeps, axis=1),
        turns=np.repeat(turn, substeps, axis=1),
    )


class Shield:
    """Keeps the planner's command if admissible, else the admissible one closest to it, else brakes."""

    def __init__(self, limits: MotionLimits | None = None, dt_s: float = 0.1, config: ShieldConfig | None = None):
        if not (math.isfinite(dt_s) and dt_s > 0):
            raise ValueError(f"shield: control period dt_s must be a finite number > 0, found {dt_s}")
        self.limits = limits or MotionLimits()
        self.dt_s = float(dt_s)
        self.config = config or ShieldConfig()
        # numpy (the reference below) or numba (viapath.compiled.shield, the same arithmetic compiled).
        self.backend = shield_backend(self.config.compute)
        self._kernel_settings: tuple[Any, ...] | None = (
            None  # the compiled test's constants (and what they were made of)
        )
        # Within one cycle of a shielded planner (:meth:`remembering`), the verdicts on single commands: the
        # planner tests its chosen command against this observation and the filter then tests the same one.
        self._verdicts: dict[Any, Any] | None = None
        # The designated path whose corridor the robot must stay in (set by its owner each cycle; None: no
        # corridor, e.g. no path yet). Only read when ``config.keep_in_corridor``.
        self.corridor: DesignatedPath | None = None

    # -- the test --------------------------------------------------------------------------------

    def evaluate(self, observation: Observation, commands: np.ndarray) -> dict[str, np.ndarray]:
        """For each command (K, 2): ``admissible``, ``friendly``, ``meet_time_s`` (inf: never),
        ``person`` (row of the first person met, -1 none) and ``achieved`` (v, ω) of the first period.
        A person already touching the robot makes every command inadmissible (``contact`` is True)."""
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

    def _evaluate(self, observation: Observation, commands: np.ndarray) -> dict[str, np.ndarray]:
        if self.backend == "numba":
            out = self._evaluate_compiled(observation, commands)
        else:
            out = self._evaluate_people(observation, commands)
        swept: list[Sweep] = []  # the commands' braking sweep, made once for both checks below

        def sweep() -> Sweep:
            if not swept:
                swept.append(self._braking_sweep(observation, out["achieved"]))
            return swept[0]

        if observation.obstacles.static_mask is not None:
            self._and_static(observation, out, sweep)
        if self._corridor_active():
            self._and_corridor(observation, out, sweep)
        return out

    def _braking_sweep(self, observation: Observation, achieved: np.ndarray) -> Sweep:
        robot = observation.robot
        substeps = max(1, math.ceil(self.dt_s / self.config.substep_s - 1e-9))
        position = np.asarray(robot.position, dtype=float)
        return braking_sweep(
            position, float(robot.heading_rad), achieved, self.limits, self.dt_s, substeps, float(robot.speed_mps)
        )

    def _corridor_active(self) -> bool:
        return self.corridor is not None and self.config.keep_in_corridor

    def _and_corridor(
        self, observation: Observation, out: dict[str, np.ndarray], sweep_of: Callable[[], Sweep]
    ) -> None:
        """The corridor (DESIGN §11: it is hard) in the verdicts of ``out``: a command is admissible only if
        its braking sweep keeps the robot's centre inside the corridor, or, for a robot already outside,
        no further out than it is now. Checked at every sub-interval end, each padded by its chord's sagitta
        (the arc between two ends bulges from its chord by at most that). Sets ``corridor_exit_time_s``
        (inf: never) and ANDs ``admissible`` and ``friendly``."""
        corridor, robot = self.corridor, observation.robot
        assert corridor is not None
        achieved = out["achieved"]
        k = len(achieved)
        exit_time = np.full(k, np.inf)
        out["corridor_exit_time_s"] = exit_time
        if float(robot.speed_mps) == 0.0 and not np.any(achieved[:, 0] != 0.0):
            return  # at rest and staying at rest: nothing moves
        position = np.asarray(robot.position, dtype=float)
        allowed = max(0.0, float(corridor.corridor_excess(position))) + _CORRIDOR_TOLERANCE_M
        sweep = sweep_of()
        ends = sweep.positions[:, 1:]  # (K, T-1, 2)
        excess = corridor.corridor_excess(ends.reshape(-1, 2)).reshape(ends.shape[:2]) + sweep.sagitta_m
        leaves = (excess > allowed) & sweep.moving
        exit_time[:] = np.where(leaves.any(axis=1), sweep.times_s[1:][np.argmax(leaves, axis=1)], np.inf)
        ok = ~leaves.any(axis=1)
        out["admissible"] = out["admissible"] & ok
        out["friendly"] = out["friendly"] & ok

    def _and_static(self, observation: Observation, out: dict[str, np.ndarray], sweep_of: Callable[[], Sweep]) -> None:
        """Static geometry (DESIGN §10) in the verdicts of ``out``: a command is admissible only if its
        braking sweep also keeps the robot ``margin_m`` from every static disc, unless the sweep never
        brings it nearer to that disc than it is now (a robot that is too close already may move away).
        Static discs do not move, so their radius does not grow (no σ, no person acceleration).
        Exact per sub-interval: the distance from a disc centre to the robot's chord, less the chord's
        sagitta pad. Sets ``static_meet_time_s`` (inf: never) and ANDs ``admissible`` and ``friendly``."""
        config, robot = self.config, observation.robot
        statics = observation.obstacles.statics()
        achieved = out["achieved"]
        k = len(achieved)
        meet = np.full(k, np.inf)
        out["static_meet_time_s"] = meet
        position = np.asarray(robot.position, dtype=float)
        distance = np.hypot(*(statics.positions - position).T)
        reach = float(robot.radius_m) + statics.radii_m + config.margin_m
        fastest = float(np.max(np.abs(achieved[:, 0]), initial=0.0))
        t_bound = fastest / max(self.limits.max_accel_mps2, 1e-9) + 2.0 * self.dt_s
        near = distance - reach <= fastest * t_bound + 1e-6
        if not near.any() or fastest == 0.0:
            return
        centres, reach, distance = statics.positions[near], reach[near], distance[near]
        sweep = sweep_of()
        low = sweep.positions.min(axis=(0, 1)) - reach.max() - float(sweep.sagitta_m.max(initial=0.0))
        high = sweep.positions.max(axis=(0, 1)) + reach.max() + float(sweep.sagitta_m.max(initial=0.0))
        inside = ((centres >= low) & (centres <= high)).all(axis=1)  # only discs the sweeps' box can reach
        if not inside.any():
            return
        centres, reach, distance = centres[inside], reach[inside], distance[inside]
        a, b = sweep.positions[:, :-1], sweep.positions[:, 1:]  # (K, T-1, 2) chords
        chord = b - a
        length2 = np.einsum("kti,kti->kt", chord, chord)
        rel = centres[None, None] - a[:, :, None]  # (K, T-1, n, 2)
        f = np.clip(np.einsum("ktni,kti->ktn", rel, chord) / np.where(length2 > 0, length2, 1.0)[..., None], 0.0, 1.0)
        closest = rel - f[..., None] * chord[:, :, None]
        gap = np.hypot(closest[..., 0], closest[..., 1]) - sweep.sagitta_m[..., None]  # (K, T-1, n)
        meets = (gap < reach[None, None]) & (gap < distance[None, None] - 1e-9) & sweep.moving[..., None]
        hit = meets.any(axis=2)  # (K, T-1)
        when = np.where(hit.any(axis=1), sweep.times_s[np.argmax(hit, axis=1)], np.inf)
        meet[:] = when
        ok = ~np.isfinite(when)
        out["admissible"] = out["admissible"] & ok
        out["friendly"] = out["friendly"] & ok

    def _evaluate_people(self, observation: Observation, commands: np.ndarray) -> dict[str, np.ndarray]:
        config, robot = self.config, observation.robot
        people = observation.obstacles.people().finite()
        achieved = achieved_first_period(
            commands, float(robot.speed_mps), float(robot.turn_rate_radps), self.limits, self.dt_s
        )
        k = len(achieved)
        position = np.asarray(robot.position, dtype=float)
        out = {
            "achieved": achieved,
            "admissible": np.ones(k, dtype=bool),
            "friendly": np.ones(k, dtype=bool),
            "meet_time_s": np.full(k, np.inf),
            "person": np.full(k, -1),
            "contact": np.zeros(1, dtype=bool),
        }
        if len(people) == 0:
            return out
        offset = people.positions - position
        distance = np.hypot(offset[:, 0], offset[:, 1])
        touching = float(robot.radius_m) + people.radii_m
        gap = distance - touching
        speed_people = np.hypot(people.velocities[:, 0], people.velocities[:, 1])
        if self._out_of_reach(achieved, people, distance, touching, gap, speed_people):
            return out
        substeps = max(1, math.ceil(self.dt_s / config.substep_s - 1e-9))
        sweep = braking_sweep(
            position, float(robot.heading_rad), achieved, self.limits, self.dt_s, substeps, float(robot.speed_mps)
        )
        if np.any(gap <= 0.0):
            out["admissible"][:] = False
            out["friendly"][:] = False
            first = int(np.argmin(gap))
            out["person"][:] = first
            out["meet_time_s"][:] = 0.0
            out["contact"][:] = True
            return out
        k_sigma = config.sigma_multiplier
        base = touching + np.minimum(config.margin_m + k_sigma * people.position_sigma_m, gap)  # (N,)
        growth = k_sigma * people.velocity_sigma_mps  # (N,) m/s
        near = self._near_sweep(sweep, people, offset, base, growth, speed_people)
        if config.mode == "passive-friendly":
            self._friendly(
                out, sweep, people, base, growth, config.person_accel_mps2, np.ones(len(people), dtype=bool) & near
            )
        if sweep.moving.shape[1] == 0 or not np.any(near):
            return out
        times = sweep.times_s
        idx = np.flatnonzero(near)
        for chunk in np.array_split(idx, max(1, math.ceil(len(idx) / 16))):
            hit = self._hits(sweep, people, chunk, base, growth, speed_people, k, substeps)  # (K, n, T - 1)
            any_hit = hit.any(axis=2)  # (K, n)
            if not np.any(any_hit):
                continue
            first_n = np.where(hit.any(axis=2), np.argmax(hit, axis=2), hit.shape[2])  # (K, n)
            first_t = np.where(any_hit, times[np.minimum(first_n + 1, len(times) - 1)], np.inf)
            best = np.argmin(first_t, axis=1)
            best_t = first_t[np.arange(k), best]
            better = best_t < out["meet_time_s"]
            out["meet_time_s"] = np.where(better, best_t, out["meet_time_s"])
            out["person"] = np.where(better, chunk[best], out["person"])
        out["admissible"] = ~np.isfinite(out["meet_time_s"])
        out["friendly"] &= out["admissible"]
        return out

    def _out_of_reach(
        self,
        achieved: np.ndarray,
        people: Obstacles,
        distance: np.ndarray,
        touching: np.ndarray,
        gap: np.ndarray,
        speed_people: np.ndarray,
    ) -> bool:
        """The cheap bound: nobody touching the robot, and nobody within reach of its longest braking (from
        the fastest first period, 2 periods slack for the discrete steps): then no sweep is needed at all."""
        config = self.config
        fastest = float(np.max(np.abs(achieved[:, 0]), initial=0.0))
        a_robot = max(self.limits.max_accel_mps2, 1e-9)
        t_bound = fastest / a_robot + 2.0 * self.dt_s
        r_bound = fastest * t_bound
        grow_bound = (
            touching
            + config.margin_m
            + config.sigma_multiplier * (people.position_sigma_m + people.velocity_sigma_mps * t_bound)
            + 0.5 * config.person_accel_mps2 * t_bound**2
            + speed_people * t_bound
        )
        if config.mode == "passive-friendly":
            grow_bound = grow_bound + speed_people**2 / (2.0 * max(config.person_accel_mps2, 1e-3))
        return bool(np.all(gap > 0.0) and np.all(distance - grow_bound > r_bound + 1e-6))

    def _near_sweep(
        self,
        sweep: Sweep,
        people: Obstacles,
        offset: np.ndarray,
        base: np.ndarray,
        growth: np.ndarray,
        speed_people: np.ndarray,
    ) -> np.ndarray:
        """Which people can matter: those whose forecast path (centre over [0, horizon], grown to its
        largest radius) comes within the robot's longest sweep of its start."""
        accel = self.config.person_accel_mps2
        horizon = float(sweep.times_s[-1])
        reach_people = base + growth * horizon + 0.5 * accel * horizon**2 + speed_people * horizon
        if self.config.mode == "passive-friendly":
            braking = speed_people**2 / (2.0 * max(accel, 1e-3))
            reach_people = reach_people + braking
        path = people.velocities * horizon
        pp = np.sum(path * path, axis=1)
        along = np.clip(np.sum(-offset * path, axis=1) / np.where(pp > 0, pp, 1.0), 0.0, 1.0)
        closest = offset + path * along[:, None]
        return (
            np.hypot(closest[:, 0], closest[:, 1]) - (reach_people - speed_people * horizon)
            <= float(np.max(sweep.reach_m, initial=0.0)) + 1e-6
        )

    def _hits(
        self,
        sweep: Sweep,
        people: Obstacles,
        chunk: np.ndarray,
        base: np.ndarray,
        growth: np.ndarray,
        speed_people: np.ndarray,
        k: int,
        substeps: int,
    ) -> np.ndarray:
        """(K, n, T - 1): whether the robot, braking along each command's sweep, meets person ``chunk[j]``'s
        growing disc within each sub-interval (and, with ``towards_only``, may move towards its centre then, or
        earlier in the same control period: the at-fault metric reads the heading at the start of the period
        in which a contact begins, and a robot that turns away during the period is still at fault)."""
        accel = self.config.person_accel_mps2
        times = sweep.times_s
        centres = (
            people.positions[chunk, None, :] + people.velocities[chunk, None, :] * times[None, :, None]
        )  # (n, T, 2)
        radii = base[chunk, None] + growth[chunk, None] * times + 0.5 * accel * times**2  # (n, T)
        rel = sweep.positions[:, None, :, :] - centres[None]  # (K, n, T, 2)
        r_a, w = rel[:, :, :-1], np.diff(rel, axis=2)
        # Radius over a sub-interval: the chord of a convex function lies above it, so the linear
        # interpolation R_a + dR tau (plus the arc's sagitta) bounds it; |r_a + w tau| < R_a + dR tau
        # is then a quadratic inequality in tau, solved exactly on [0, 1].
        # The arc strays from its chord by at most 4 sagitta * tau (zero at the start: a person on the
        # disc's edge now is not met by a robot moving away from it).
        r_start = np.broadcast_to(radii[None, :, :-1], (k,) + radii[:, :-1].shape)
        d_r = np.diff(radii, axis=1)[None] + 4.0 * sweep.sagitta_m[:, None, :]
        qa = np.sum(w * w, axis=-1) - d_r * d_r
        qb = 2.0 * (np.sum(r_a * w, axis=-1) - r_start * d_r)
        qc = np.sum(r_a * r_a, axis=-1) - r_start * r_start
        low = np.minimum(qc, qa + qb + qc)
        vertex = -qb / np.where(qa > 0, 2.0 * qa, 1.0)
        inside = (qa > 0) & (vertex > 0.0) & (vertex < 1.0)
        low = np.where(inside, np.minimum(low, qc - qb * qb / np.where(qa > 0, 4.0 * qa, 1.0)), low)
        hit = (low < -1e-12) & sweep.moving[:, None, :]  # rounding at the edge is no meeting
        if self.config.towards_only:
            # Towards the person's centre, which may lie anywhere within the forecast's own uncertainty of the
            # forecast centre (k σ_p + k σ_v t + a_p t²/2, largest at the sub-interval's end), since the metric
            # reads the real centre.
            k_sigma = self.config.sigma_multiplier
            spread = (
                k_sigma * people.position_sigma_m[chunk, None]
                + growth[chunk, None] * times[None, 1:]
                + 0.5 * accel * times[None, 1:] ** 2
            )  # (n, T - 1)
            # Only while the robot moves towards the person's centre: T = u . (c - p) = -u . rel. Its
            # largest value on the sub-interval is at most (T_a + T_b + L h) / 2, L bounding |dT/dt|.
            heading = sweep.headings
            ux, uy = np.cos(heading) * 1.0, np.sin(heading) * 1.0
            s_int = sweep.speeds[:, None, :]
            t_a = -s_int * (ux[:, None, :-1] * r_a[..., 0] + uy[:, None, :-1] * r_a[..., 1])
            r_b = r_a + w
            t_b = -s_int * (ux[:, None, 1:] * r_b[..., 0] + uy[:, None, 1:] * r_b[..., 1])
            r_max = np.maximum(np.hypot(r_a[..., 0], r_a[..., 1]), np.hypot(r_b[..., 0], r_b[..., 1])) + 0.01
            lipschitz = np.abs(s_int) * (
                np.abs(sweep.turns[:, None, :]) * r_max + speed_people[chunk][None, :, None] + np.abs(s_int)
            )
            h_int = float(times[1] - times[0])
            towards = (t_a + t_b + lipschitz * h_int + 2.0 * np.abs(s_int) * spread[None]) > 0.0  # (K, n, T - 1)
            periods = towards.reshape(towards.shape[:2] + (-1, substeps))
            hit &= np.logical_or.accumulate(periods, axis=3).reshape(towards.shape)
        return hit

    def _evaluate_compiled(self, observation: Observation, commands: np.ndarray) -> dict[str, np.ndarray]:
        """The test above, compiled (:func:`viapath.compiled.shield.shield`: same arithmetic,
        same verdicts), with the achieved (v, ω) and the dropping of non-finite people in the same call."""
        kernels = require("shield")
        config, robot, people = self.config, observation.robot, observation.obstacles.people()
        limits_array, settings = self._settings_arrays()
        state = _robot_array(robot)
        achieved, admissible, friendly, meet, person, contact = kernels.shield(
            state,
            limits_array,
            _c(np.reshape(commands, (-1, 2))),
            False,
            0,
            0,
            _c(people.positions),
            _c(people.velocities),
            _c(people.radii_m),
            _c(people.position_sigma_m),
            _c(people.velocity_sigma_mps),
            settings,
            config.mode == "passive-friendly",
            bool(config.towards_only),
        )[:6]
        return {
            "achieved": achieved,
            "admissible": admissible,
            "friendly": friendly,
            "meet_time_s": meet,
            "person": person,
            "contact": np.full(1, contact),
        }

    def _settings_arrays(self) -> tuple[np.ndarray, np.ndarray]:
        """The compiled test's constants: limits (max speed, accel, turn rate, turn accel) and settings
        (dt, substeps, margin, k sigma, person accel), made again only when what they come from changes."""
        config = self.config
        key = (self.limits, self.dt_s, config)
        cached = self._kernel_settings
        if cached is None or cached[2] != key:
            limits = self.limits
            substeps = max(1, math.ceil(self.dt_s / config.substep_s - 1e-9))
            cached = self._kernel_settings = (
                np.array(
                    [
                        limits.max_speed_mps,
                        limits.max_accel_mps2,
                        limits.max_turn_rate_radps,
                        limits.max_turn_accel_radps2,
                    ],
                    dtype=np.float64,
                ),
                np.array(
                    [self.dt_s, substeps, config.margin_m, config.sigma_multiplier, config.person_accel_mps2],
                    dtype=np.float64,
                ),
                key,
            )
        return cached[0], cached[1]

    def _friendly(
        self,
        out: dict[str, np.ndarray],
        sweep: Sweep,
        people: Obstacles,
        base: np.ndarray,
        growth: np.ndarray,
        accel: float,
        near: np.ndarray,
    ) -> None:
        """Passive friendly: the person, braking from its forecast at the robot's rest time, stops short."""
        idx = np.flatnonzero(near)
        if len(idx) == 0:
            return
        t_rest = sweep.rest_time_s[:, None]  # (K, 1)
        velocity = people.velocities[idx]  # (n, 2)
        speed = np.hypot(velocity[:, 0], velocity[:, 1])
        start = people.positions[idx][None] + velocity[None] * t_rest[..., None]  # (K, n, 2)
        travel = velocity * (speed / (2.0 * max(accel, 1e-3)))[:, None]  # (n, 2)
        radius = base[idx][None] + growth[idx][None] * t_rest + 0.5 * accel * t_rest**2  # (K, n)
        rel = sweep.rest_position[:, None, :] - start  # (K, n, 2)
        tt = np.sum(travel * travel, axis=-1)
        f = np.clip(np.sum(rel * travel[None], axis=-1) / np.where(tt > 0, tt, 1.0), 0.0, 1.0)
        closest = rel - travel[None] * f[..., None]
        dist = np.hypot(closest[..., 0], closest[..., 1])
        out["friendly"] &= ~np.any(dist < radius, axis=1)

    # -- the filter ------------------------------------------------------------------------------

    def candidates(self, observation: Observation, command: Command) -> np.ndarray:
        """The planner's command, the hardest braking, and a grid over the dynamic window (K, 2)."""
        robot, limits, n = observation.robot, self.limits, int(self.config.samples)
        corners = achieved_first_period(
            np.array([[0.0, -limits.max_turn_rate_radps], [limits.max_speed_mps, limits.max_turn_rate_radps]]),
            float(robot.speed_mps),
            float(robot.turn_rate_radps),
            limits,
            self.dt_s,
        )
        v = np.linspace(corners[0, 0], corners[1, 0], n)
        w = np.linspace(corners[0, 1], corners[1, 1], n)
        grid = np.stack(np.meshgrid(v, w, indexing="ij"), axis=-1).reshape(-1, 2)
        planner = np.array([[command.speed_mps, command.turn_rate_radps]], dtype=float)
        planner_reached = achieved_first_period(
            planner, float(robot.speed_mps), float(robot.turn_rate_radps), limits, self.dt_s
        )
        # The planner's turn rate at slower speeds, and its speed at other turn rates: the likeliest picks.
        slower = np.stack([v, np.full(n, planner_reached[0, 1])], axis=1)
        turned = np.stack([np.full(n, planner_reached[0, 0]), w], axis=1)
        return np.concatenate([planner, [[0.0, 0.0]], slower, turned, grid])

    def filter(self, observation: Observation, command: Command) -> ShieldResult:
        """What goes to the base instead of ``command`` (the planner's), and why; says which backend ran."""
        result = self._filter(observation, command)
        # The result was made just now and is seen by no one yet: set its backend in place rather than copy
        # all its fields with dataclasses.replace (every cycle).
        object.__setattr__(result, "backend", self.backend)
        return result

    def _filter(self, observation: Observation, command: Command) -> ShieldResult:
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
            return ShieldResult(
                command,
                original,
                False,
                "admissible",
                True,
                True if friendly_mode else None,
                candidates=1,
                admissible_candidates=1,
            )
        person_id, meet, why = self._first_meeting(observation, own)
        stop = Command.stop()
        if bool(own["contact"][0]):
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
        static_meet = float(own.get("static_meet_time_s", _NEVER)[0])
        if math.isfinite(static_meet) and (meet is None or static_meet < meet):
            person_id, meet = None, static_meet
        corridor_exit = float(own.get("corridor_exit_time_s", _NEVER)[0])
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
        stop = Command.stop()
        pick, passive_pick, tested, passing, reached = self._search(observation, command)
        if pick is not None:
            text = (
                f"not friendly ({why}): closest friendly command"
                if friendly_mode
                else f"{why}: closest admissible command"
            )
            return ShieldResult(
                self._as_command(reached, pick),
                original,
                True,
                text,
                True,
                True if friendly_mode else None,
                person_id,
                meet,
                tested + 1,
                passing,
            )
        common: dict[str, Any] = dict(
            person_id=person_id, meet_time_s=meet, candidates=tested + 1, admissible_candidates=passing + int(own_ok)
        )
        if friendly_mode and own_ok:
            return ShieldResult(
                command, original, False, "admissible (no friendly command exists)", True, False, **common
            )
        if passive_pick is not None:
            return ShieldResult(
                self._as_command(reached, passive_pick),
                original,
                True,
                f"{why}: closest admissible command (no friendly one)",
                True,
                False,
                **common,
            )
        return ShieldResult(
            stop,
            original,
            not _same(original, stop),
            f"{why}: none admissible, hardest braking",
            False,
            False if friendly_mode else None,
            **common,
        )

    def _search(
        self, observation: Observation, command: Command
    ) -> tuple[int | None, int | None, int, int, np.ndarray]:
        """The window search when the planner's command fails: the wanted (friendly in passive-friendly
        mode, else admissible) candidate closest to it, the closest admissible one, how many were tested
        and passed, and the candidates' achieved (v, ω)."""
        if self.backend == "numba" and observation.obstacles.static_mask is None:
            found = self._search_compiled(observation, command)
            # The compiled search knows people only. Its picks are the first admissible ones in the search's
            # order; if they keep to the corridor too, they are also the first that are admissible with it.
            if not self._corridor_active() or self._keep_to_corridor(observation, found):
                return found
        friendly_mode = self.config.mode == "passive-friendly"
        limits = self.limits
        # Candidates closest first (each axis over its limit, ties to the slower), tested in chunks:
        # the first chunk holding an admissible one holds the closest admissible one.
        commands = self.candidates(observation, command)
        reached = achieved_first_period(
            commands, float(observation.robot.speed_mps), float(observation.robot.turn_rate_radps), limits, self.dt_s
        )
        scale = np.array([max(limits.max_speed_mps, 1e-9), max(limits.max_turn_rate_radps, 1e-9)])
        distance = np.sum(((reached - reached[0]) / scale) ** 2, axis=1)
        order = np.lexsort((reached[:, 0], distance))
        order = order[order != 0]  # the planner's own command is judged already
        passive_pick, tested, passing = None, 0, 0
        for chunk in np.array_split(order, max(1, math.ceil(len(order) / _CHUNK))):
            check = self.evaluate(observation, commands[chunk])
            tested += len(chunk)
            passing += int(check["admissible"].sum())
            wanted = check["friendly"] if friendly_mode else check["admissible"]
            if np.any(wanted):
                return int(chunk[np.argmax(wanted)]), passive_pick, tested, passing, reached
            if passive_pick is None and np.any(check["admissible"]):
                passive_pick = int(chunk[np.argmax(check["admissible"])])
        return None, passive_pick, tested, passing, reached

    def _keep_to_corridor(
        self, observation: Observation, found: tuple[int | None, int | None, int, int, np.ndarray]
    ) -> bool:
        pick, passive_pick, _, _, reached = found
        picks = [index for index in (pick, passive_pick) if index is not None]
        if not picks:
            return True
        verdict = {
            "achieved": reached[picks],
            "admissible": np.ones(len(picks), bool),
            "friendly": np.ones(len(picks), bool),
        }
        self._and_corridor(observation, verdict, lambda: self._braking_sweep(observation, verdict["achieved"]))
        return bool(verdict["admissible"].all())

    def _search_compiled(
        self, observation: Observation, command: Command
    ) -> tuple[int | None, int | None, int, int, np.ndarray]:
        """:meth:`_search` compiled (:func:`viapath.compiled.shield.shield`: same candidates, order and chunks)."""
        kernels = require("shield")
        config, robot, people = self.config, observation.robot, observation.obstacles
        limits_array, settings = self._settings_arrays()
        state = _robot_array(robot)
        reached, _, _, _, _, _, pick, passive_pick, tested, passing = kernels.shield(
            state,
            limits_array,
            np.array([[command.speed_mps, command.turn_rate_radps]], dtype=np.float64),
            True,
            int(config.samples),
            _CHUNK,
            _c(people.positions),
            _c(people.velocities),
            _c(people.radii_m),
            _c(people.position_sigma_m),
            _c(people.velocity_sigma_mps),
            settings,
            config.mode == "passive-friendly",
            bool(config.towards_only),
        )
        return (
            int(pick) if pick >= 0 else None,
            int(passive_pick) if passive_pick >= 0 else None,
            int(tested),
            int(passing),
            reached,
        )

    @staticmethod
    def _as_command(reached: np.ndarray, index: int) -> Command:
        if index == 1:  # the hardest braking itself
            return Command.stop()
        return Command(float(reached[index, 0]), float(reached[index, 1]))


def _robot_array(robot: RobotState) -> np.ndarray:
    """x, y, heading, speed, turn rate, radius: the compiled kernels' robot state."""
    position = robot.position
    return np.array(
        [position[0], position[1], robot.heading_rad, robot.speed_mps, robot.turn_rate_radps, robot.radius_m],
        dtype=np.float64,
    )


def _c(array: ArrayLike) -> np.ndarray:
    return np.ascontiguousarray(array, dtype=np.float64)


def shield_backend(choice: str) -> str:
    """``numpy`` or ``numba`` for the option value: as the planner's (:func:`resolve_backend`), except
    that a plain ``auto`` takes numba only once the compiled shield needs no compilation."""
    backend = resolve_backend(choice)
    if backend == "numba" and not explicit(choice) and not ready(require("shield").shield):
        return "numpy"
    return backend


def precompile() -> bool:
    """Compile the shield's kernels now if numba is there and they are not compiled yet (about 12 s,
    once per machine: numba caches them on disk); True when the compiled shield is ready."""
    if not numba_available():
        return False
    if not ready(require("shield").shield):
        shield = Shield(config=ShieldConfig(compute="numba"))
        people = Obstacles(np.array([[1.0, 0.0]]), np.array([[-0.5, 0.0]]), np.array([0.25]))
        observation = Observation(0.0, RobotState(np.zeros(2), 0.0, 0.3, 0.0, 0.25), people)
        shield.filter(observation, Command(0.5, 0.0))  # the planner's command fails: the search compiles too
    return True


def _same(a: Command, b: Command) -> bool:
    return a.speed_mps == b.speed_mps and a.turn_rate_radps == b.turn_rate_radps
