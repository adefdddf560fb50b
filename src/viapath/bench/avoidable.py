"""Could any robot on this drive have avoided an at-fault contact? A search that knows the recorded future.

An evaluation tool, not part of the core: it reads where every person *will* walk from the episode's
trace, which no planner can know. For each at-fault onset with a person
(:func:`viapath.sim.metrics.at_fault_onsets`) it starts from the robot's real state at the step the
person is first seen (:func:`viapath.sim.metrics.first_seen_steps`: the simulator hands the planner
the person, with the velocity they walk at, in that very cycle, so a robot could react to them there)
and tries command sequences the drive can follow (:func:`viapath.kinematics.limit_command`: speed and
turn rate ramp towards a target at the acceleration limits, exact arcs in between):

* decisions are held for ``hold`` steps: the time from the appearance to the onset is cut into
  ``max_levels`` decisions (finer when the person appeared late: single steps when it appeared within
  ``max_levels`` steps of the onset), each held at most ``max_hold_s`` (more decisions then); after
  the onset time the same hold goes on;
* each decision is one of 3 speed targets (0, the present speed, the top speed) × 5 turn-rate targets
  (−1, −½, 0, ½, 1 × the top turn rate);
* after every decision (and at the start) the hardest braking until rest is tried as well. A robot at
  rest has no at-fault onset, now or later (the rule needs it to move faster than 0.05 m/s), so a
  braking that reaches rest without an at-fault onset proves the contact **avoidable** and ends the
  search (exact pruning);
* a branch with an at-fault onset (with anyone, judged with everyone's recorded future by the rule of
  ``at_fault_onsets``, written again here over many sequences) is dropped: every continuation has it.

The contact is **unavoidable** when every branch is dropped. When the search would exceed its budget
(the person appeared too long before the onset for these holds, or too many branches survive), the
contact counts as **avoidable**: the search could not show otherwise. People who react to the robot
(``replay.react``) have no recorded future: their contacts count as avoidable too.

Static geometry is not part of the search (the at-fault rule of people is): a contact with a wall
while the robot moves is always the robot's fault and counts as avoidable.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from viapath.observation import MotionLimits
from viapath.sim.metrics import appeared_in_step, at_fault_onsets, first_seen_steps, static_contact_onsets

MIN_SPEED_MPS = 0.05  # the at-fault rule's speed threshold (viapath.sim.metrics.at_fault_onsets)
TURN_FRACTIONS = (-1.0, -0.5, 0.0, 0.5, 1.0)  # turn-rate targets, × the top turn rate
MAX_LEVELS = 4  # decisions between the appearance and the onset (15^4 branches at most there)
MAX_HOLD_S = 1.0  # a decision is never held longer
MAX_BRANCHES = 200_000  # live branches at once
MAX_STEP_WORK = 60_000_000  # branch × step × person evaluations in one search


@dataclass
class Verdict:
    """The search's answer for one at-fault onset with a person."""

    person: int
    onset_step: int
    onset_s: float
    appeared_s: float
    robot_speed_at_appearance_mps: float
    avoidable: bool
    reason: str  # "braking at ... avoids it", "no sequence avoids it", "budget", "reactive people"
    hold_s: float = 0.0
    branches: int = 0

    @property
    def appeared_before_onset_s(self) -> float:
        return self.onset_s - self.appeared_s


@dataclass
class _World:
    """The trace's recorded future as the search needs it (rows past the trace's end repeat the last)."""

    people: np.ndarray  # (T, N, 2), NaN while absent
    appeared: np.ndarray  # (T, N): appears in step t (the exemption of overlap_on_appearance)
    radii: np.ndarray  # (N,) person radius + robot radius
    dt_s: float
    limits: MotionLimits
    brake_steps: int
    columns: np.ndarray = field(default_factory=lambda: np.zeros(0, int))

    def rows(self, first: int, last: int) -> np.ndarray:
        """People at steps first..last (inclusive), only the columns searched."""
        index = np.minimum(np.arange(first, last + 1), len(self.people) - 1)
        return self.people[index][:, self.columns]

    def appeared_rows(self, first: int, last: int) -> np.ndarray:
        index = np.arange(first, last + 1)
        inside = index < len(self.appeared)
        out = np.zeros((len(index), len(self.columns)), dtype=bool)
        out[inside] = self.appeared[index[inside]][:, self.columns]
        return out


def drive(states: np.ndarray, speed_targets: np.ndarray, turn_targets: np.ndarray, limits: MotionLimits, dt_s: float):
    """K branches from ``states`` (K, 5: x, y, heading, speed, turn rate), each commanding the targets
    (K, J) step by step, as :func:`viapath.kinematics.step` does: poses (K, J+1, 3) and speeds
    (K, J+1) at the start of each step, and the end states (K, 5)."""
    k, steps = speed_targets.shape
    poses = np.empty((k, steps + 1, 3))
    speeds = np.empty((k, steps + 1))
    x, y, heading, v, w = (states[:, i].astype(float).copy() for i in range(5))
    poses[:, 0] = np.stack([x, y, heading], axis=1)
    speeds[:, 0] = v
    dv, dw = limits.max_accel_mps2 * dt_s, limits.max_turn_accel_radps2 * dt_s
    for j in range(steps):
        v_cmd = np.clip(speed_targets[:, j], 0.0, limits.max_speed_mps)
        w_cmd = np.clip(turn_targets[:, j], -limits.max_turn_rate_radps, limits.max_turn_rate_radps)
        v = v + np.clip(v_cmd - v, -dv, dv)
        w = w + np.clip(w_cmd - w, -dw, dw)
        half = 0.5 * w * dt_s
        small = np.abs(half) < 1e-6
        sinc = np.where(small, 1.0 - half * half / 6.0, np.sin(half) / np.where(small, 1.0, half))
        chord = v * dt_s * sinc
        x = x + chord * np.cos(heading + half)
        y = y + chord * np.sin(heading + half)
        new_heading = heading + w * dt_s
        heading = np.arctan2(np.sin(new_heading), np.cos(new_heading))
        poses[:, j + 1] = np.stack([x, y, heading], axis=1)
        speeds[:, j + 1] = v
    return poses, speeds, np.stack([x, y, heading, v, w], axis=1)


def _touching(start: np.ndarray, end: np.ndarray, reach: np.ndarray) -> np.ndarray:
    """Robot-minus-person offsets at a step's start and end (..., 2), NaN where the person is absent:
    does their distance, moving linearly over the step, come under ``reach``?"""
    present = np.isfinite(start).all(-1) & np.isfinite(end).all(-1)
    start = np.where(present[..., None], start, 1e9)
    motion = np.where(present[..., None], end, 1e9) - start
    speed_sq = np.sum(motion * motion, axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        tau = np.clip(np.where(speed_sq > 0, -np.sum(start * motion, axis=-1) / speed_sq, 0.0), 0.0, 1.0)
    closest = start + motion * tau[..., None]
    return present & (np.hypot(closest[..., 0], closest[..., 1]) < reach)


def segment_faults(world: _World, poses: np.ndarray, speeds: np.ndarray, first_step: int, contact_before: np.ndarray):
    """At-fault onsets of K branches over steps first_step.. (poses (K, J+1, 3), speeds (K, J+1) at
    each step's start), given each branch's contact flags in the step before (K, N): the onsets
    (K, J, N) and the contact flags of the last step (K, N)."""
    steps = poses.shape[1] - 1
    people = world.rows(first_step, first_step + steps)  # (J+1, N, 2)
    start = poses[:, :-1, None, :2] - people[None, :-1]
    end = poses[:, 1:, None, :2] - people[None, 1:]
    contact = _touching(start, end, world.radii[world.columns])  # (K, J, N)
    previous = np.concatenate([contact_before[:, None], contact[:, :-1]], axis=1)
    heading = poses[:, :-1, 2]
    velocity = speeds[:, :-1, None] * np.stack([np.cos(heading), np.sin(heading)], axis=-1)
    towards = np.einsum("kjd,kjnd->kjn", velocity, -np.nan_to_num(start, nan=1e9)) > 0.0
    with np.errstate(invalid="ignore"):
        overlapping = world.appeared_rows(first_step, first_step + steps - 1)[None] & (
            np.hypot(start[..., 0], start[..., 1]) < world.radii[world.columns]
        )
    onsets = contact & ~previous & towards & (speeds[:, :-1, None] > MIN_SPEED_MPS) & ~overlapping
    return onsets, contact[:, -1]


def make_world(trace, limits: MotionLimits) -> _World:
    people = np.asarray(trace.obstacle_positions, dtype=float)
    present = np.isfinite(people[:-1]).all(-1) & np.isfinite(people[1:]).all(-1)  # as overlap_on_appearance
    appeared = appeared_in_step(people) & present
    dv = limits.max_accel_mps2 * trace.dt_s
    return _World(
        people=people,
        appeared=appeared,
        radii=np.asarray(trace.obstacle_radii_m, dtype=float) + trace.robot_radius_m,
        dt_s=trace.dt_s,
        limits=limits,
        brake_steps=int(math.ceil(limits.max_speed_mps / dv)) + 2,
        columns=np.arange(people.shape[1]),
    )


def _real_state(trace, step: int) -> np.ndarray:
    x, y, heading = trace.robot_poses[step]
    return np.array([[x, y, heading, trace.robot_speeds_mps[step], trace.robot_turn_rates_radps[step]]])


def _real_contact(trace, world: _World, step: int) -> np.ndarray:
    """The real robot's contact flags in the step before ``step`` (none before the first)."""
    if step == 0:
        return np.zeros((1, len(world.columns)), dtype=bool)
    start = trace.robot_poses[step - 1, :2] - world.people[step - 1][world.columns]
    end = trace.robot_poses[step, :2] - world.people[step][world.columns]
    return _touching(start, end, world.radii[world.columns])[None]


def search(
    trace,
    limits: MotionLimits,
    first_step: int,
    onset_step: int,
    max_levels: int = MAX_LEVELS,
    max_hold_s: float = MAX_HOLD_S,
    max_branches: int = MAX_BRANCHES,
    max_work: int = MAX_STEP_WORK,
) -> tuple[bool | None, str, float, int]:
    """From the real state at ``first_step``: (True if some sequence avoids every at-fault onset, False if
    none does, None if over budget; how; the hold in seconds; branches tried)."""
    world = make_world(trace, limits)
    dt = trace.dt_s
    span = max(onset_step - first_step, 1)
    hold = max(1, min(math.ceil(span / max_levels), int(math.floor(max_hold_s / dt + 1e-9))))
    end_step = onset_step + 4 * world.brake_steps  # after that, a surviving branch is not chased further
    # Only people present somewhere in the steps any branch can reach matter.
    horizon = end_step + hold + world.brake_steps
    window = world.people[first_step : min(horizon, len(world.people) - 1) + 1]
    world.columns = np.flatnonzero(np.isfinite(window).all(-1).any(0))
    states = _real_state(trace, first_step)
    contact = _real_contact(trace, world, first_step)
    step = first_step
    tried = 0
    work = 0
    top_turn = limits.max_turn_rate_radps
    while True:
        # The hardest braking from every live branch.
        k = len(states)
        faulty, _, _ = _hold(world, states, np.zeros(k), np.zeros(k), world.brake_steps, step, contact)
        tried += k
        work += k * world.brake_steps * max(len(world.columns), 1)
        if not faulty.all():
            return True, f"braking {(step - first_step) * dt:.1f} s after the appearance avoids it", hold * dt, tried
        if step >= end_step:
            return None, "budget: branches without an onset outlive the search", hold * dt, tried
        # Every decision for the next ``hold`` steps.
        speed_targets = np.stack([np.zeros(k), states[:, 3], np.full(k, limits.max_speed_mps)], axis=1)  # (k, 3)
        turn_targets = np.asarray(TURN_FRACTIONS) * top_turn  # (5,)
        v_target = np.repeat(speed_targets, len(TURN_FRACTIONS), axis=1).reshape(-1)
        w_target = np.tile(turn_targets, 3 * k)
        parents = np.repeat(np.arange(k), 3 * len(TURN_FRACTIONS))
        if len(parents) > max_branches:
            return None, f"budget: more than {max_branches} live branches", hold * dt, tried
        faulty, ends, last_contact = _hold(world, states[parents], v_target, w_target, hold, step, contact[parents])
        work += len(parents) * hold * max(len(world.columns), 1)
        tried += len(parents)
        alive = ~faulty
        if not alive.any():
            return False, "no sequence avoids it", hold * dt, tried
        if work > max_work:
            return None, "budget: too much work", hold * dt, tried
        states, contact = ends[alive], last_contact[alive]
        # Identical branches (targets that the limits make equal) are searched once.
        key = np.concatenate([np.round(states, 12), contact.astype(float)], axis=1)
        _, unique = np.unique(key, axis=0, return_index=True)
        states, contact = states[np.sort(unique)], contact[np.sort(unique)]
        step += hold


def _hold(world: _World, states, speed_targets, turn_targets, steps: int, first_step: int, contact, chunk: int = 4000):
    """K branches each holding one (speed, turn-rate) target for ``steps``: whether each has an at-fault
    onset (K,), the end states (K, 5) and the last step's contact flags (K, N); in chunks of branches,
    so that the (branches, steps, people, 2) arrays stay small."""
    faulty = np.empty(len(states), dtype=bool)
    ends = np.empty_like(states)
    last = np.empty((len(states), len(world.columns)), dtype=bool)
    for start in range(0, len(states), chunk):
        part = slice(start, start + chunk)
        n = len(states[part])
        poses, speeds, ends[part] = drive(
            states[part],
            np.repeat(speed_targets[part, None], steps, axis=1),
            np.repeat(turn_targets[part, None], steps, axis=1),
            world.limits,
            world.dt_s,
        )
        onsets, last[part] = segment_faults(world, poses, speeds, first_step, contact[part])
        faulty[part] = onsets.reshape(n, -1).any(axis=1)
    return faulty, ends, last


def judge(trace, limits: MotionLimits, reactive: bool = False, **budget) -> list[Verdict]:
    """A verdict for each at-fault onset with a person in the trace (in time order)."""
    onsets = at_fault_onsets(trace)
    verdicts = []
    for k, person in zip(*np.nonzero(onsets)):
        appeared = int(first_seen_steps(trace.obstacle_positions[: k + 1])[person])
        verdict = Verdict(
            person=int(person),
            onset_step=int(k),
            onset_s=float(trace.times_s[k]),
            appeared_s=float(trace.times_s[appeared]),
            robot_speed_at_appearance_mps=float(trace.robot_speeds_mps[appeared]),
            avoidable=True,
            reason="reactive people: no recorded future",
        )
        if not reactive:
            found, verdict.reason, verdict.hold_s, verdict.branches = search(trace, limits, appeared, int(k), **budget)
            verdict.avoidable = found is not False
        verdicts.append(verdict)
    return verdicts


def check_replay(trace, limits: MotionLimits, first_step: int = 0) -> None:
    """The search's model against the episode itself: the real commands (the trace's speeds and turn
    rates, as targets) give back the trace's poses and the metric's at-fault onsets. Raises ValueError."""
    world = make_world(trace, limits)
    last = len(trace.robot_poses) - 1
    speeds_true = np.asarray(trace.robot_speeds_mps[first_step + 1 : last + 1])[None]
    turns_true = np.asarray(trace.robot_turn_rates_radps[first_step + 1 : last + 1])[None]
    poses, speeds, _ = drive(_real_state(trace, first_step), speeds_true, turns_true, limits, trace.dt_s)
    error = float(np.max(np.abs(poses[0, :, :2] - trace.robot_poses[first_step:, :2])))
    if error > 1e-6:
        raise ValueError(f"the search's drive model is off the trace by {error:.2e} m")
    mine, _ = segment_faults(world, poses, speeds, first_step, _real_contact(trace, world, first_step))
    metric = at_fault_onsets(trace)[first_step:]
    if not np.array_equal(mine[0], metric):
        raise ValueError("the search's at-fault rule disagrees with viapath.sim.metrics.at_fault_onsets on the trace")


def contact_speeds(trace) -> list[tuple[float, str, float]]:
    """Every contact's onset (person or static), in time order: (time s, "person n" | "static", the
    robot's speed at the onset's step start, m/s)."""
    poses = trace.robot_poses
    obstacles = trace.obstacle_positions
    found = []
    if obstacles.shape[1] and len(poses) > 1:
        start = poses[:-1, None, :2] - obstacles[:-1]
        end = poses[1:, None, :2] - obstacles[1:]
        contact = _touching(start, end, np.asarray(trace.obstacle_radii_m) + trace.robot_radius_m)
        onset = contact & ~np.vstack([np.zeros((1, contact.shape[1]), dtype=bool), contact[:-1]])
        for k, n in zip(*np.nonzero(onset)):
            found.append((float(trace.times_s[k]), f"person {n}", float(trace.robot_speeds_mps[k])))
    for k in np.flatnonzero(static_contact_onsets(trace)):
        found.append((float(trace.times_s[k]), "static", float(trace.robot_speeds_mps[k])))
    return sorted(found)


def episode_columns(trace, scenario, with_fault: bool) -> dict:
    """The bench's columns of one episode: contact speeds always; the avoidable / unavoidable split
    of the at-fault contacts when ``with_fault`` (the episode's at_fault_collision)."""
    speeds = contact_speeds(trace)
    row: dict = {
        "contact_speed_max_mps": max((s for _, _, s in speeds), default=None),
        "contact_speeds": " ".join(f"{t:.1f}s:{who.replace(' ', '')}:{s:.2f}" for t, who, s in speeds),
        "at_fault_avoidable": 0,
        "at_fault_unavoidable": 0,
        "unavoidable_appeared_before_s": "",
        "at_fault_detail": "",
    }
    if not with_fault:
        return row
    limits = MotionLimits(**scenario.robot.limits.model_dump())
    reactive = any(
        getattr(getattr(item, "replay", None), "react", False) for item in getattr(scenario, "obstacles", []) or []
    )
    verdicts = judge(trace, limits, reactive=reactive)
    static = int(np.count_nonzero(static_contact_onsets(trace) & (np.asarray(trace.robot_speeds_mps[:-1]) > 0.05)))
    row["at_fault_avoidable"] = sum(v.avoidable for v in verdicts) + static
    row["at_fault_unavoidable"] = sum(not v.avoidable for v in verdicts)
    row["unavoidable_appeared_before_s"] = " ".join(
        f"{v.appeared_before_onset_s:.1f}" for v in verdicts if not v.avoidable
    )
    details = [
        f"person {v.person} at {v.onset_s:.1f}s (appeared {v.appeared_before_onset_s:.1f}s before, "
        f"{v.robot_speed_at_appearance_mps:.2f} m/s then): {'avoidable' if v.avoidable else 'UNAVOIDABLE'}, {v.reason}"
        for v in verdicts
    ]
    if static:
        details.append(f"{static} static contact(s) while moving: avoidable")
    row["at_fault_detail"] = "; ".join(details)
    return row
