"""What kind of contact each contact of an episode is: how the robot met it and whether the person's
constant-velocity forecast saw it coming.

Source: the planner forecasts each person at their current velocity (docs/explanation/beyond-the-paper.md);
a contact the forecast of one or two seconds before already showed is one the planner had the time to see,
one it missed came from a person who changed course. What we chose where nothing says more:

* **At rest**: the robot's speed at the onset's step start is below ``AT_REST_MPS`` (the bench's
  ``contact_speeds`` column prints it as 0.00). Otherwise **moving**; a moving contact that is not at fault has
  the person walking into the robot's side or back (viapath.sim.metrics.at_fault_onsets).
* **The forecast** made ``lead_s`` before the onset is the person's position and velocity then, held over
  ``FORECAST_S``; it **saw** the contact when it comes within ``SAW_WITHIN_M`` of touching the robot's disc
  where the robot stood at the onset. The kinds, first match:

  - ``straight``: the forecast of 2 s before saw it and the person turned less than ``STRAIGHT_DEG`` over those
    2 s (groups and hallway walkers);
  - ``turned 1-2 s before``: the forecast of 1 s before saw it;
  - ``turned in the last 1 s``: the forecast of 1 s before missed it (a person who changed course in the last
    second: a constant-velocity forecast cannot see it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

AT_REST_MPS = 0.005  # below this the robot is at rest (contact_speeds prints 0.00)
FORECAST_S = 4.0  # how far a forecast is held
SAW_WITHIN_M = 0.05  # a forecast that comes this near touching saw the contact
STRAIGHT_DEG = 15.0  # a person turning less than this over 2 s walks straight
KINDS = ("straight", "turned 1-2 s before", "turned in the last 1 s")


@dataclass(frozen=True)
class ContactKind:
    time_s: float
    person: int
    robot_speed_mps: float
    at_rest: bool
    kind: str  # one of KINDS
    turn_2s_deg: float  # how much the person's heading changed over the 2 s before the onset
    forecast_gap_1s_m: float  # how near touching the forecast of 1 s before came (negative: overlap)
    forecast_gap_2s_m: float


def forecast_gap(
    position: np.ndarray, velocity: np.ndarray, robot_xy: np.ndarray, radius_sum_m: float, dt_s: float
) -> float:
    """The smallest gap between the disc of a person forecast from ``position`` at ``velocity`` over
    ``FORECAST_S`` (sampled every ``dt_s``) and the robot's disc standing at ``robot_xy``; nan for no position."""
    if not (np.all(np.isfinite(position)) and np.all(np.isfinite(velocity))):
        return math.nan
    times = np.arange(0.0, FORECAST_S + 0.5 * dt_s, dt_s)
    centres = position[None, :] + times[:, None] * velocity[None, :]
    return float(np.min(np.hypot(*(centres - robot_xy[None, :]).T)) - radius_sum_m)


def heading_change_deg(v_then: np.ndarray, v_now: np.ndarray) -> float:
    """The angle between two velocities (0 if either is standing or unknown)."""
    if not (np.all(np.isfinite(v_then)) and np.all(np.isfinite(v_now))):
        return 0.0
    if np.hypot(*v_then) < 0.05 or np.hypot(*v_now) < 0.05:
        return 0.0
    change = math.atan2(float(v_now[1]), float(v_now[0])) - math.atan2(float(v_then[1]), float(v_then[0]))
    return abs(math.degrees((change + math.pi) % (2.0 * math.pi) - math.pi))


def classify_onset(
    person_positions: np.ndarray,
    person_velocities: np.ndarray,
    robot_xy: np.ndarray,
    step: int,
    dt_s: float,
    radius_sum_m: float,
) -> tuple[str, float, float, float]:
    """The kind of a contact that begins in ``step`` (:data:`KINDS`), the person's turn over 2 s, and the gaps of
    the forecasts of 1 s and 2 s before. ``person_positions``, ``person_velocities``: (K, 2) per step."""
    back_1 = max(step - int(round(1.0 / dt_s)), 0)
    back_2 = max(step - int(round(2.0 / dt_s)), 0)
    gap_1 = forecast_gap(person_positions[back_1], person_velocities[back_1], robot_xy, radius_sum_m, dt_s)
    gap_2 = forecast_gap(person_positions[back_2], person_velocities[back_2], robot_xy, radius_sum_m, dt_s)
    turn = heading_change_deg(person_velocities[back_2], person_velocities[max(step - 1, 0)])
    if gap_2 < SAW_WITHIN_M and turn < STRAIGHT_DEG:
        kind = KINDS[0]
    elif gap_1 < SAW_WITHIN_M:
        kind = KINDS[1]
    else:
        kind = KINDS[2]
    return kind, turn, gap_1, gap_2


def contact_kinds(trace) -> list[ContactKind]:
    """Every contact with a person of an episode's trace, in time order, with its kind."""
    from viapath.bench.avoidable import contact_speeds

    found = []
    for time_s, who, speed in contact_speeds(trace):
        if who == "static":
            continue
        person = int(who.split()[1])
        step = int(round(time_s / trace.dt_s))
        kind, turn, gap_1, gap_2 = classify_onset(
            trace.obstacle_positions[:, person],
            trace.obstacle_velocities[:, person],
            trace.robot_poses[step, :2],
            step,
            trace.dt_s,
            float(trace.obstacle_radii_m[person] + trace.robot_radius_m),
        )
        found.append(ContactKind(time_s, person, speed, speed < AT_REST_MPS, kind, turn, gap_1, gap_2))
    return found
