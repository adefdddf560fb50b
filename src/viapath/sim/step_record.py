"""One planning cycle of the closed loop, as handed to ``run_episode(on_step=...)`` (views, recorders).

Source: docs/design.md §9 (seeing a run). The loop builds one record per cycle, after the planner decided
and before the robot moves; a callback must not change what it is given. Fields hold the loop's
own objects (no copies), so a record costs nothing when nobody keeps it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class StepRecord:
    step: int  # index of the cycle (row of the trace)
    time_s: float  # simulated time
    state: Any  # kinematics.UnicycleState before the command is applied (x, y, heading_rad, speed_mps, turn_rate_radps)
    observation: Any  # viapath.observation.Observation the planner was given
    decision: Any  # viapath.planning.Decision it returned
    plan_time_ms: float  # wall time of the planner call
    world: Any  # sim.perception.WorldSnapshot: the true world at this instant
    scans: list | None  # the laser perception's raw scans (one array per scanner), None without lasers
    perception: Any  # the perception object (laser: scanners, detections, blind region)
    planner: Any  # the planner object (its configuration: horizon, uncertainty cone)
