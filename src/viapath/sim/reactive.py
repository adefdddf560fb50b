"""Reactive replays: recorded pedestrians who follow their own tracks but give way to the robot.

Used for ``replay: {..., react: true}`` (docs/design.md §4). Benchmarks that make ETH/UCY
people "reactive" (e.g. the pedestrian simulators of crowd-navigation benchmarks: a social force
from the robot, with the person pulled back towards the recorded trajectory) move each person by a
social-force model whose goal is the recording itself. We do the same with our own social force
(:mod:`viapath.sim.social_force`, Helbing & Molnár 1995), written for the *deviation* from the
recording so that a person the robot never disturbs stays exactly on their track.

Person i at simulated time t is at ``p_i = r_i(t) + e_i`` with velocity ``u_i = r'_i(t) + w_i``
(``r_i``: the recording, interpolated linearly between rows as for plain replays; ``r'_i``: the
velocity of that interpolation). The deviation obeys

    dw_i/dt = (-e_i / T_back - w_i) / tau  +  f_robot(p_i, u_i)

which is Helbing's driving term ``(v0 - u)/tau`` with the desired velocity
``v0 = r'_i(t) + (r_i(t) - p_i) / T_back`` ("pulled back towards where the recording has them now"),
plus the recording's own acceleration fed forward (so an undisturbed person has e = w = 0 exactly).

What the sources leave open and we chose:

* **Relaxation** ``tau = 0.5 s`` (Helbing's value) and **return time** ``T_back = 2.0 s``: with
  ``T_back = 4 tau`` the return to the track is critically damped (double pole at ``-1/(2 tau)``):
  no overshoot, the deviation decays like ``(1 + t/1 s) exp(-t/1 s)`` once the robot is gone.
* **Force from the robot**: Helbing's elliptic potential (Eq. 4) with the robot as pedestrian b,
  ``V0 = 2.1 m²/s²``, ``sigma = 0.3 m`` (range), ``Δt = 2 s`` along the robot's velocity, distances
  surface to surface (person radius + robot radius), as in :mod:`viapath.sim.social_force`. Its
  magnitude is ``V0/sigma·exp(-b/sigma)``: 7 m/s² at contact, 0.25 m/s² at 1 m gap, negligible
  beyond ~2 m. Field of view as there: weight 1 within ±100° of the walking direction, 0.5 behind.
* **Stepping aside**: a pure repulsion stops a person dead in front of a robot standing on their
  track (the symmetric head-on deadlock of social-force models). We add a sideways term of the
  same magnitude times ``max(0, cos φ)`` (φ: angle between the walking direction and the robot),
  perpendicular to the walking direction, on the side away from the robot — to the walker's right
  on an exact tie (keep-right convention). Walking direction: the recording's velocity, or the
  direction away from the robot for someone whose recording stands still (< 0.1 m/s).
* **Speed cap**: ``|u_i| <= max(1.3 |r'_i(t)|, 1.0 m/s)`` (Helbing's 1.3 v0, Eq. 11; at least
  1 m/s so that a recorded standing person can still step away).
* People react to the robot only, not to one another: the recordings already hold their mutual
  avoidance, and a deviation is short and local. Reactive people do not see walls.
* Integration: semi-implicit Euler at ``step_s = 0.05 s`` (two sub-steps per 0.1 s cycle); during
  one cycle the robot is taken where it was at the start of the cycle (what people saw last).
* A person enters the scene on their track (e = w = 0) and leaves it when their recording ends —
  except that nobody enters *inside or against* the robot: a person whose recording begins less
  than ``spawn_gap_m = 0.3 m`` (surface to surface) from the robot enters that far from it, pushed
  straight away from the robot's centre (and is then pulled back to the track like any deviation).
  A real person would have walked round the robot before entering the recorded area; without this
  rule 3 of viapath's 4 contacts on the first ``eth-ucy-react`` run were people appearing
  overlapping the robot (present for 0 s), which no planner can avoid. People present at the
  episode's first step are not moved (the suites keep everyone 1 m from the start).
* The velocity given to the planner is, as for plain replays (:func:`viapath.io.eth_ucy.replay_states`),
  a backward difference over one row step of the person's *actual* positions: the recording's
  estimate plus the backward difference of the deviation.

Identity: non-reactive replays and the other obstacles keep the values of
:func:`viapath.sim.obstacles.scenario_obstacle_states`; the closed loop uses this module only when
some replay reacts, so episodes without one are computed exactly as before.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from viapath.io.eth_ucy import PedestrianTrack, load_tracks, replay_states
from viapath.sim.obstacles import scenario_obstacle_states


@dataclass(frozen=True)
class ReactiveParams:
    relaxation_time_s: float = 0.5  # tau
    return_time_s: float = 2.0  # T_back
    robot_strength_m2ps2: float = 2.1  # V0
    robot_range_m: float = 0.3  # sigma
    robot_step_time_s: float = 2.0  # Δt of the elliptic potential
    sideways_weight: float = 1.0
    field_of_view_rad: float = np.radians(100.0)
    outside_view_weight: float = 0.5
    max_speed_factor: float = 1.3
    min_speed_cap_mps: float = 1.0
    standing_speed_mps: float = 0.1
    spawn_gap_m: float = 0.3
    step_s: float = 0.05


def robot_force(positions, walking, robot_position, robot_velocity, surface_m, params: ReactiveParams):
    """Acceleration (N, 2) the robot exerts on people at ``positions`` walking along ``walking`` (N, 2)."""
    p = np.asarray(positions, float)
    r = p - np.asarray(robot_position, float)  # from the robot to the person
    centre = np.maximum(np.hypot(r[:, 0], r[:, 1]), 1e-9)
    # Surface distance expressed as a centre distance, as in social_force._agent_forces.
    r = r * (np.maximum(centre - surface_m, 1e-3) / centre)[:, None]
    s = np.asarray(robot_velocity, float)[None, :] * params.robot_step_time_s
    r_norm = np.maximum(np.hypot(r[:, 0], r[:, 1]), 1e-9)
    rs = r - s
    rs_norm = np.maximum(np.hypot(rs[:, 0], rs[:, 1]), 1e-9)
    b = 0.5 * np.sqrt(np.maximum((r_norm + rs_norm) ** 2 - np.sum(s * s, axis=1), 1e-12))
    b = np.maximum(b, 1e-6)
    grad_b = ((r_norm + rs_norm) / (4.0 * b))[:, None] * (r / r_norm[:, None] + rs / rs_norm[:, None])
    magnitude = params.robot_strength_m2ps2 / params.robot_range_m * np.exp(-b / params.robot_range_m)
    repulsion = magnitude[:, None] * grad_b
    # Walking direction: the recording's, else away from the robot.
    walking = np.asarray(walking, float)
    speed = np.hypot(walking[:, 0], walking[:, 1])
    away = r / r_norm[:, None]
    heading = np.where((speed > params.standing_speed_mps)[:, None], walking / np.maximum(speed, 1e-9)[:, None], away)
    to_robot = -away
    cos_phi = np.sum(heading * to_robot, axis=1)
    weight = np.where(cos_phi >= np.cos(params.field_of_view_rad), 1.0, params.outside_view_weight)
    left = np.column_stack([-heading[:, 1], heading[:, 0]])
    robot_on_left = heading[:, 0] * to_robot[:, 1] - heading[:, 1] * to_robot[:, 0]
    side = np.where(robot_on_left > 1e-9, -1.0, np.where(robot_on_left < -1e-9, 1.0, -1.0))  # tie: right
    f_norm = np.hypot(repulsion[:, 0], repulsion[:, 1])
    sideways = (params.sideways_weight * f_norm * np.maximum(cos_phi, 0.0) * side)[:, None] * left
    return weight[:, None] * (repulsion + sideways)


class ReactiveReplay:
    """People of recorded tracks who give way to the robot; advanced one cycle at a time by :meth:`step`.

    ``times`` are the episode's step times (from 0, evenly spaced); ``start_s`` the scene time at
    episode time 0. :attr:`positions` / :attr:`velocities` (T, N, 2) hold rows 0..k after k steps
    (NaN where a person is absent), the recording beyond.
    """

    def __init__(
        self,
        tracks: list[PedestrianTrack],
        times,
        start_s: float,
        dt_s: float,
        offset=(0.0, 0.0),
        radius_m: float = 0.25,
        robot_radius_m: float = 0.25,
        params: ReactiveParams | None = None,
    ):
        self.params = params or ReactiveParams()
        self.tracks = tracks
        self.times = np.asarray(times, float)
        self.start_s = float(start_s)
        self.dt_row_s = float(dt_s)
        self.offset = np.asarray(offset, float)
        self.surface_m = float(radius_m) + float(robot_radius_m)
        n = len(tracks)
        # Until a row is stepped to, it holds the recording (exactly the plain replay's values).
        self.positions, self.velocities = replay_states(tracks, self.times + self.start_s, self.dt_row_s, offset)
        self.deviations = np.zeros((len(self.times), n, 2))  # e, per step row
        self.deviation_velocity = np.zeros((n, 2))  # w, now
        self.k = 0
        # The recording on the sub-step grid (fine index g = k * substeps + i), for the people who
        # appear during the episode only.
        cycle_s = float(self.times[1] - self.times[0]) if len(self.times) > 1 else self.params.step_s
        self.substeps = max(1, int(round(cycle_s / self.params.step_s)))
        fine_t = self.times[0] + np.arange((len(self.times) - 1) * self.substeps + 1) * (cycle_s / self.substeps)
        scene_t = fine_t + self.start_s
        first = np.array([t.times_s[0] for t in tracks]) if n else np.zeros(0)
        last = np.array([t.times_s[-1] for t in tracks]) if n else np.zeros(0)
        self.first_s = first
        self.active = np.flatnonzero((last >= scene_t[0]) & (first <= scene_t[-1]))
        m = len(self.active)
        self.present = (scene_t[:, None] >= first[self.active]) & (scene_t[:, None] <= last[self.active])
        self.recorded = np.zeros((len(fine_t), m, 2))
        self.recorded_velocity = np.zeros((len(fine_t), m, 2))
        for c, j in enumerate(self.active):
            track = tracks[j]
            self.recorded[:, c] = np.stack(
                [np.interp(scene_t, track.times_s, track.positions[:, a]) for a in (0, 1)], 1
            )
            if len(track.times_s) > 1:
                piece = np.clip(np.searchsorted(track.times_s, scene_t, side="right") - 1, 0, len(track.times_s) - 2)
                pieces = np.diff(track.positions, axis=0) / np.diff(track.times_s)[:, None]
                self.recorded_velocity[:, c] = pieces[piece]
        self.recorded_velocity[~self.present] = 0.0
        self.was_present = self.present[0].copy()

    def _fill_row(self, row: int) -> None:
        """Row ``row`` of positions and past-only velocity estimates: recording + deviation."""
        active = self.active
        g = row * self.substeps
        present = self.present[g]
        if not present.any():
            return
        idx = active[present]
        t = self.times[row]
        scene_t = t + self.start_s
        e_now = self.deviations[row, idx]
        # Backward difference over one row step, as replay_states: the recording's part is already in
        # the plain replay's velocity; add the deviation's.
        before_scene = np.maximum(scene_t - self.dt_row_s, self.first_s[idx])
        span = scene_t - before_scene
        before_t = before_scene - self.start_s
        i = np.clip(np.searchsorted(self.times, before_t, side="right") - 1, 0, max(len(self.times) - 2, 0))
        if len(self.times) > 1:
            a = np.clip((before_t - self.times[i]) / (self.times[i + 1] - self.times[i]), 0.0, 1.0)
            e_before = (1.0 - a)[:, None] * self.deviations[i, idx] + a[:, None] * self.deviations[i + 1, idx]
        else:
            e_before = np.zeros_like(e_now)
        recorded_now = self.recorded[g, present]
        self.positions[row, idx] = recorded_now + e_now + self.offset
        with np.errstate(invalid="ignore", divide="ignore"):
            deviation_rate = np.where(span[:, None] > 1e-9, (e_now - e_before) / span[:, None], 0.0)
        self.velocities[row, idx] = self.velocities[row, idx] + deviation_rate

    def _entry_deviation(self, recorded: np.ndarray, robot_position: np.ndarray) -> np.ndarray:
        """Deviation (M, 2) that puts people entering at ``recorded`` at least ``spawn_gap_m`` from the robot."""
        away = recorded - robot_position
        centre = np.hypot(away[:, 0], away[:, 1])
        wanted = self.surface_m + self.params.spawn_gap_m
        direction = np.where(centre[:, None] > 1e-9, away / np.maximum(centre, 1e-9)[:, None], np.array([1.0, 0.0]))
        return np.where((centre < wanted)[:, None], robot_position + direction * wanted - recorded, 0.0)

    # -- one cycle --------------------------------------------------------------------------------
    def step(self, robot_position, robot_velocity) -> None:
        """Advance people from step ``k`` to ``k + 1``, seeing the robot where it is at step ``k``."""
        if self.k + 1 >= len(self.times):
            return
        params = self.params
        h = (self.times[self.k + 1] - self.times[self.k]) / self.substeps
        active = self.active
        e = self.deviations[self.k, active].copy()
        w = self.deviation_velocity[active].copy()
        robot_position = np.asarray(robot_position, float) - self.offset
        robot_velocity = np.asarray(robot_velocity, float)
        for i in range(self.substeps):
            g = self.k * self.substeps + i
            present = self.present[g]
            e[~present] = 0.0
            w[~present] = 0.0
            entering = present & ~self.was_present
            self.was_present = present
            if entering.any():
                e[entering] = self._entry_deviation(self.recorded[g, entering], robot_position)
            if not present.any():
                continue
            recorded_velocity = self.recorded_velocity[g, present]
            p = self.recorded[g, present] + e[present]
            force = robot_force(p, recorded_velocity, robot_position, robot_velocity, self.surface_m, params)
            accel = (-e[present] / params.return_time_s - w[present]) / params.relaxation_time_s + force
            u = recorded_velocity + w[present] + h * accel
            speed = np.hypot(u[:, 0], u[:, 1])
            recorded_speed = np.hypot(recorded_velocity[:, 0], recorded_velocity[:, 1])
            cap = np.maximum(params.max_speed_factor * recorded_speed, params.min_speed_cap_mps)
            u = u * np.where(speed > cap, cap / np.maximum(speed, 1e-12), 1.0)[:, None]
            w[present] = u - recorded_velocity
            e[present] = e[present] + h * w[present]
        present_end = self.present[(self.k + 1) * self.substeps]
        e[~present_end] = 0.0
        w[~present_end] = 0.0
        entering = present_end & ~self.was_present
        self.was_present = present_end
        if entering.any():
            e[entering] = self._entry_deviation(self.recorded[(self.k + 1) * self.substeps, entering], robot_position)
        self.k += 1
        self.deviations[self.k, active] = e
        self.deviation_velocity[active] = w
        self._fill_row(self.k)


class ObstacleMotion:
    """All obstacles of a scenario with some reactive replay: the precomputed states for the others,
    :class:`ReactiveReplay` columns advanced by :meth:`step` (positions/velocities updated in place)."""

    def __init__(self, scenario, times):
        positions, velocities, radii = scenario_obstacle_states(scenario, times)
        self.positions, self.velocities, self.radii = positions, velocities, radii
        self.replays: list[tuple[int, ReactiveReplay]] = []
        column = 0
        for item in scenario.obstacles:
            replay = getattr(item, "replay", None)
            if replay is None:
                column += 1
                continue
            tracks = load_tracks(replay.file, replay.dt_s)
            if getattr(replay, "react", False):
                reactive = ReactiveReplay(
                    tracks, times, replay.start_s, replay.dt_s, replay.offset, replay.radius, scenario.robot.radius
                )
                self.replays.append((column, reactive))
                self._copy(column, reactive)
            column += len(tracks)

    def _copy(self, column: int, reactive: ReactiveReplay) -> None:
        n = reactive.positions.shape[1]
        self.positions[:, column : column + n] = reactive.positions
        self.velocities[:, column : column + n] = reactive.velocities

    def step(self, robot_position, robot_velocity) -> None:
        """Advance the reactive people one cycle, seeing the robot at ``robot_position`` / ``robot_velocity``."""
        for column, reactive in self.replays:
            reactive.step(robot_position, robot_velocity)
            n = reactive.positions.shape[1]
            self.positions[reactive.k, column : column + n] = reactive.positions[reactive.k]
            self.velocities[reactive.k, column : column + n] = reactive.velocities[reactive.k]


def obstacle_motion(scenario, times) -> ObstacleMotion | None:
    """An :class:`ObstacleMotion` when some replay of the scenario reacts to the robot, else ``None``."""
    if any(getattr(getattr(item, "replay", None), "react", False) for item in scenario.obstacles):
        return ObstacleMotion(scenario, times)
    return None
