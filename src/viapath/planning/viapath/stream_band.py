"""Holding short of a stream (``stream_band_s``; 0: off): a robot about to enter the band that people have been
crossing and are forecast to cross, without room to spare, stops before the band instead of in the middle of it.

Source: beyond the paper (its robot enters wherever the constant-velocity forecast leaves a free leg). Replayed
and generated people blind to the robot turn into a robot that has to yield in their stream a second or two
before they reach it, later than a constant-velocity forecast sees; most such contacts began with the robot at
rest or escaping inside the stream. Outside the band a stream sweeps over several seconds, such a turn reaches it
far less often.

What we chose:
* **The band.** Per person crossing the robot's way (faster than ``MOVING_MPS`` and at least 30° across the line
  from the robot to its subgoal: people met head-on or overtaken are passed, not waited for; a first version
  without this held the robot behind a slow walker it should overtake): the capsule from where they were
  ``stream_band_s`` ago (their track as this planner saw it; where it first saw them if later) to where they
  are, and the capsule from there to where their current velocity takes them in ``stream_band_s``, each of
  radius their check radius (robot, person, margin, position uncertainty) plus ``stream_band_margin_m``. The band is the union of the
  capsules; a point's gap to it is its distance to the nearest capsule's axis less that capsule's radius
  (negative inside). Static geometry sweeps no band.
* **When.** After the recipe and stepping aside, when the plan is ``straight``, ``avoid`` or ``slow``, the
  robot is outside the band and the plan enters it within ``ENTRY_LOOK_S``: its polyline (the plan's waypoints,
  or the leg to its target), driven at the plan's speed (a slow plan at its slow speed) and sampled every ``escape_dt_s``, from the sample
  before the band on, must keep ``stream_band_entry_clearance_m`` from every person's forecast cone (the
  capped uncertainty cones of the leg checks; the gap between samples bounded as stepping aside bounds it,
  :func:`.step_aside.clearances`). A plan that does not is replaced by a stop where the robot is (status
  ``hold-short``): the robot brakes before the band and waits there, looking again every cycle. Inside the band
  already, the plan goes on: stopping there is what this avoids. Stops, waits and escapes are left alone.
* **Only for a stream that ends.** A hold begins only when the same pass, started 1, 2 or 3 s later
  (``WAIT_LOOK_S``), would keep the entry clearance from the forecast: the stream's end is in sight. Once holding,
  the robot holds while the entry is not clear. Before a stream with no end in sight it goes on as without the band:
  on replayed pedestrians (``eth-ucy``), whose streams in the busy scenes do not end, a wait only moved the robot's
  meetings later, and the contacts it added came seconds after the hold, not during it.
* **The shield** must admit the stop; if it does not, the decision stands.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from viapath.observation import Command, Decision, Plan
from viapath.planning.viapath.checks import LegChecks
from viapath.planning.viapath.step_aside import _people_and_statics, clearances

MOVING_MPS = 0.1  # people slower than this sweep no band
CROSSING_SINE = 0.5  # a person sweeps a band when walking at least 30° across the robot's way to its subgoal
MOVING_STATUSES = frozenset({"straight", "avoid", "slow"})  # plans that may enter a band
ENTRY_LOOK_S = 3.0  # how far along its plan the robot looks for the band's edge (s)
WAIT_LOOK_S = 3.0  # how long a wait the forecast must show ending the stream for holding short to be worth it (s)


def band_gaps(points: np.ndarray, starts: np.ndarray, ends: np.ndarray, radii: np.ndarray) -> np.ndarray:
    """(M,) the gap of each point (M, 2) to the union of capsules (segment ``starts``→``ends`` (N, 2), radius
    ``radii`` (N,)): distance to the nearest axis less its radius, the smallest over capsules; inf with none."""
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    if len(starts) == 0:
        return np.full(len(points), np.inf)
    axis = ends - starts  # (N, 2)
    length2 = np.einsum("ij,ij->i", axis, axis)
    rel = points[:, None, :] - starts[None]  # (M, N, 2)
    along = np.einsum("mnj,nj->mn", rel, axis) / np.where(length2 > 0, length2, 1.0)
    along = np.clip(np.where(length2 > 0, along, 0.0), 0.0, 1.0)
    nearest = starts[None] + along[..., None] * axis[None]
    distance = np.hypot(points[:, None, 0] - nearest[..., 0], points[:, None, 1] - nearest[..., 1])
    return (distance - radii[None]).min(axis=1)


class StreamBand:
    """The people's recent tracks (by id) and the band they sweep, kept by one planner across cycles."""

    def __init__(self) -> None:
        self._tracks: dict[int, list[tuple[float, np.ndarray]]] = {}
        self.holding = False  # whether last cycle held short

    def reset(self) -> None:
        self._tracks.clear()
        self.holding = False

    def observe(self, time_s: float, checks: LegChecks, window_s: float) -> None:
        """Record this cycle's people (static rows left out); forget what is older than ``window_s``."""
        obstacles = checks.obstacles
        mask = obstacles.static_mask
        seen: set[int] = set()
        for row, person in enumerate(np.asarray(obstacles.ids).tolist()):
            if mask is not None and mask[row]:
                continue
            track = self._tracks.setdefault(int(person), [])
            track.append((time_s, np.array(obstacles.positions[row], dtype=float)))
            while len(track) > 1 and track[1][0] <= time_s - window_s:
                track.pop(0)
            seen.add(int(person))
        for person in [p for p in self._tracks if p not in seen]:
            del self._tracks[person]

    def capsules(self, checks: LegChecks, window_s: float, margin_m: float) -> tuple[np.ndarray, ...]:
        """(starts, ends, radii) of the band's capsules: a crossing person's past (start → now) and forecast (now
        → end) each as one capsule."""
        obstacles = checks.obstacles
        mask = obstacles.static_mask
        way = checks.subgoal - checks.position
        way = way / max(float(np.hypot(*way)), 1e-9)
        starts, ends, radii = [], [], []
        for row, person in enumerate(np.asarray(obstacles.ids).tolist()):
            if mask is not None and mask[row]:
                continue
            velocity = np.asarray(obstacles.velocities[row], dtype=float)
            speed = float(np.hypot(*velocity))
            if speed < MOVING_MPS or abs(way[0] * velocity[1] - way[1] * velocity[0]) < CROSSING_SINE * speed:
                continue  # standing, or walking along the robot's way (met head-on or overtaken, not crossed)
            now = np.asarray(obstacles.positions[row], dtype=float)
            radius = float(checks.check_radii[row]) + margin_m
            track = self._tracks.get(int(person))
            past = track[0][1] if track else now
            starts += [past, now]
            ends += [now, now + velocity * window_s]
            radii += [radius, radius]
        if not starts:
            empty = np.zeros((0, 2))
            return empty, empty, np.zeros(0)
        return np.array(starts), np.array(ends), np.array(radii)


def along_polyline(points: np.ndarray, speed_mps: float, dt: float, steps: int) -> np.ndarray:
    """(steps + 1, 2) positions every ``dt`` along the polyline ``points`` at ``speed_mps``, standing at its end."""
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    lengths = np.hypot(*np.diff(points, axis=0).T) if len(points) > 1 else np.zeros(0)
    cumulative = np.concatenate([[0.0], np.cumsum(lengths)])
    travelled = np.minimum(np.arange(steps + 1) * dt * max(speed_mps, 0.0), cumulative[-1])
    return np.stack([np.interp(travelled, cumulative, points[:, i]) for i in range(2)], axis=1)


def forecast_from(checks: LegChecks, t0_s: float) -> tuple[np.ndarray, ...]:
    """The people's forecast cones (:func:`.step_aside.clearances`' arguments) seen from ``t0_s`` ahead: centres
    moved on by ``v t0``, radii grown to ``t0`` and the growth's remaining time shortened by ``t0``."""
    positions, velocities, radii, growth, until = _people_and_statics(checks, checks.packed_obstacles())[0]
    grown = radii + growth * np.minimum(t0_s, until)
    return positions + velocities * t0_s, velocities, grown, growth, np.maximum(until - t0_s, 0.0)


def _waiting_clears(positions: np.ndarray, dt: float, checks: LegChecks, t0_s: float, needed_m: float) -> bool:
    """Whether the same pass (``positions`` every ``dt`` from ``t0_s`` on), started some whole seconds later up to
    WAIT_LOOK_S, keeps ``needed_m`` from everyone's forecast: the stream ends in sight."""
    for wait_s in np.arange(1.0, WAIT_LOOK_S + 0.5, 1.0):
        if float(clearances(positions[None], dt, *forecast_from(checks, t0_s + wait_s))[0]) >= needed_m:
            return True
    return False


def hold_short(planner: Any, checks: LegChecks, decision: Decision, band: StreamBand) -> Decision | None:
    """A stop before the band, instead of a moving plan that enters it with less than
    ``stream_band_entry_clearance_m`` from someone's forecast while in it; None: the decision stands.
    (:meth:`StreamBand.observe` is the caller's, once per cycle.)"""
    config = planner.config
    held, band.holding = band.holding, False
    if decision.plan.status not in MOVING_STATUSES or len(checks.obstacles) == 0:
        return None
    starts, ends, radii = band.capsules(checks, config.stream_band_s, config.stream_band_margin_m)
    if len(starts) == 0 or band_gaps(checks.position, starts, ends, radii)[0] < 0.0:
        return None  # no stream, or in it already: the plan goes on
    plan = decision.plan
    points = plan.waypoints if len(plan.waypoints) >= 2 else np.array([checks.position, plan.target])
    dt = config.escape_dt_s
    positions = along_polyline(points, plan.speed_mps, dt, int(round(ENTRY_LOOK_S / dt)))
    gaps = band_gaps(positions, starts, ends, radii)
    entering = gaps < 0.0
    if not entering.any():
        return None
    # From the sample before the band on: a pass through the band only while it keeps clear of everyone.
    start = max(int(np.argmax(entering)) - 1, 0)
    clearance = float(clearances(positions[None, start:], dt, *forecast_from(checks, start * dt))[0])
    if clearance >= config.stream_band_entry_clearance_m:
        return None
    if not held and not _waiting_clears(
        positions[start:], dt, checks, start * dt, config.stream_band_entry_clearance_m
    ):
        return None  # a stream the forecast shows no end of within WAIT_LOOK_S: waiting only delays the same entry
    stop = Plan(
        "hold-short",
        0.0,
        checks.position.copy(),
        subgoal_index=checks.subgoal_index,
        extras={"hold_short": {"instead_of": plan.status, "clearance_m": clearance}},
    )
    if not planner._inside_shield(stop):
        return None
    band.holding = True
    return Decision(Command.stop(), stop)
