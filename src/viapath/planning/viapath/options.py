"""The paper planner's options, each defined once (name, default, unit, bounds, help).

Defaults are the paper's where it gives one (speed set 0.1…0.5 m/s and the weights of Eq. 1, §4.2)
and docs/design.md §2's choices elsewhere. The safety margin and the uncertainty inflation are common to
every planner (:data:`viapath.planning.base.COMMON_OPTIONS`).
"""

from __future__ import annotations

from viapath.options import Option, OptionSet, Retired
from viapath.planning.base import COMMON_OPTIONS

_OWN = [
    # The paper (§3, §4.2).
    Option(
        "speeds",
        (0.1, 0.2, 0.3, 0.4, 0.5),
        "the speed set: candidates are built for each, plus the current and the nominal speed",
        "m/s",
        minimum=0.01,
        maximum=50.0,
    ),
    Option("k1", 0.1, "Eq. 1 weight of the path length Dist", "1/m", minimum=0.0, maximum=1000.0, group="weights"),
    Option(
        "k2",
        0.01,
        "Eq. 1 weight of the travel time (the paper's 0.001 is preset 'paper'; docs/howto/tune-weights.md)",
        "1/s",
        minimum=0.0,
        maximum=1000.0,
        group="weights",
    ),
    Option("k3", 0.08, "Eq. 1 weight of |v - v_nominal|", "s/m", minimum=0.0, maximum=1000.0, group="weights"),
    Option(
        "k4",
        0.3,
        "Eq. 1 weight of the turn θ onto the first leg",
        "1/rad",
        minimum=0.0,
        maximum=1000.0,
        group="weights",
    ),
    Option(
        "theta_unit", "rad", "unit of θ in Eq. 1 (degrees make the θ term swamp the others)", choices=("rad", "deg")
    ),
    # docs/design.md §2: how via points and legs are checked.
    Option(
        "planning_margin_m",
        0.1,
        "via points are placed this much outside the checked disc",
        "m",
        minimum=0.0,
        maximum=2.0,
    ),
    Option(
        "horizon_s",
        10.0,
        "legs are checked against the forecast up to this time",
        "s",
        minimum=0.0,
        exclusive_minimum=True,
        maximum=60.0,
    ),
    Option("max_depth", 3, "how many via points a candidate may chain (graph search depth)", minimum=1, maximum=6),
    Option(
        "max_root_obstacles",
        12,
        "obstacles branched on at the root, earliest contact first (0: all)",
        minimum=0,
        maximum=1000,
    ),
    Option(
        "corridor_check_spacing_m",
        0.05,
        "spacing of the points that check a leg against the corridor",
        "m",
        minimum=0.005,
        maximum=1.0,
    ),
    # Beyond the paper: the way back to the path after an avoidance (docs/howto/tune-weights.md §6).
    Option(
        "return_lookahead_m",
        0.5,
        "off the path line, first try the straight leg at the nominal speed to the "
        "path point this far ahead of the robot (before the subgoal), so it returns within about this distance "
        "rather than on the shallow line to a far subgoal (0: off, the paper's way)",
        "m",
        minimum=0.0,
        maximum=100.0,
    ),
    # Ties and churn.
    Option("preferred_side", "left", "near-ties (head-on) go round this side", choices=("left", "right")),
    Option("side_tolerance", 0.03, "cost added to passing on the other side", minimum=0.0, maximum=1000.0),
    Option(
        "hysteresis",
        0.05,
        "cost bonus for last cycle's way round (and half more for its speed)",
        minimum=0.0,
        maximum=1000.0,
    ),
    Option(
        "keep_previous_way",
        True,
        "a way round that vanished is re-checked with less inflation and kept if still cheaper",
    ),
    Option(
        "keep_previous_inflation", 0.25, "... with this fraction of the uncertainty inflation", minimum=0.0, maximum=1.0
    ),
    Option(
        "switch_inflation",
        2.0,
        "while last cycle's way round is still free, a new way round (other than slowing or waiting) is taken "
        "only if it is free with this multiple of the uncertainty inflation (σ terms and the cone's cap; 1: off)",
        minimum=1.0,
        maximum=10.0,
    ),
    Option(
        "outrun_hold_s",
        1.0,
        "outrunning someone from behind: the slowest faster straight speed whose leg stays free this "
        "long past the horizon (0: the cheapest, back to nominal as soon as free)",
        "s",
        minimum=0.0,
        maximum=30.0,
    ),
    # Slowing down and waiting.
    Option(
        "slow_leg_inflation",
        0.25,
        "fraction of the uncertainty inflation the first, slow leg of a slow/wait candidate is checked with",
        minimum=0.0,
        maximum=1.0,
    ),
    Option(
        "creep_speed_mps",
        0.05,
        "slow/wait candidates may also creep at this speed, below the speed set (0: not)",
        "m/s",
        minimum=0.0,
        maximum=50.0,
    ),
    Option(
        "standing_cost",
        0.002,
        "cost of each second a slow/wait candidate first stands still (Eq. 1 ties standing T with "
        "creeping at half the nominal speed for 2T)",
        "1/s",
        minimum=0.0,
        maximum=1000.0,
    ),
    Option(
        "slow_times_s",
        (0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 5.0, 6.0),
        "how long a candidate may first stand or drive slower than nominal",
        "s",
        minimum=0.0,
        exclusive_minimum=True,
        maximum=30.0,
    ),
    # Motion limits: roll-outs of the first leg.
    Option(
        "rollout_heading_rad",
        0.35,
        "a candidate whose first leg turns more than this is rolled out",
        "rad",
        minimum=0.0,
        maximum=3.15,
    ),
    Option(
        "rollout_s",
        2.0,
        "how long a candidate's first leg is rolled out",
        "s",
        minimum=0.0,
        exclusive_minimum=True,
        maximum=30.0,
    ),
    Option("rollout_dt_s", 0.1, "step of the roll-outs", "s", minimum=0.01, maximum=1.0),
    Option(
        "turn_in_place_min_rad",
        0.02,
        "a plan whose roll-out leaves the corridor turns on the spot first when its heading error is above this",
        "rad",
        minimum=0.0,
        maximum=3.15,
    ),
    Option("max_rollouts", 8, "candidates rolled out, cheapest first, before falling back", minimum=1, maximum=1000),
    Option(
        "heading_gain",
        2.5,
        "turn rate per radian of heading error when steering for the target",
        "1/s",
        minimum=0.0,
        exclusive_minimum=True,
        maximum=100.0,
    ),
    # No free candidate.
    Option(
        "escape_s",
        3.0,
        "how long each escape command is rolled out",
        "s",
        minimum=0.0,
        exclusive_minimum=True,
        maximum=30.0,
    ),
    Option("escape_dt_s", 0.1, "step of the escape roll-outs", "s", minimum=0.01, maximum=1.0),
    Option(
        "calm_escape",
        True,
        "escape no faster than the top of the speed set, without flipping from one cycle to the next",
    ),
    Option(
        "escape_continuity_s",
        0.5,
        "with calm_escape: time to contact an escape command pays for being far from last cycle's",
        "s",
        minimum=0.0,
        maximum=60.0,
    ),
    Option(
        "escape_progress_s",
        0.01,
        "time to contact an escape command that stays clear over its whole roll-out gains per m/s of progress "
        "towards the subgoal (0.01: progress only breaks ties, and the calm escape's continuity keeps last cycle's "
        "command; 5 s²/m: the robot escapes onwards)",
        "s²/m",
        minimum=0.0,
        maximum=60.0,
    ),
    Option(
        "escape_max_excess_m",
        0.5,
        "an escape may take the robot at most this far outside the corridor (standing is always allowed)",
        "m",
        minimum=0.0,
        maximum=100.0,
    ),
    # Stepping aside (step_aside.py): a standing or waiting robot leaves the way of someone walking at it.
    Option(
        "step_aside_s",
        3.0,
        "a stop, wait, blocked wait or escape from rest that keeps less than step_aside_clearance_m from "
        "someone's forecast over this time gives way to a move inside the corridor that keeps clear (0: off)",
        "s",
        minimum=0.0,
        maximum=30.0,
    ),
    Option(
        "step_aside_clearance_m",
        0.2,
        "clearance beyond the checked disc that a standing robot keeps from the forecast by stepping aside",
        "m",
        minimum=0.0,
        maximum=5.0,
    ),
    Option(
        "step_aside_distances_m",
        (0.3, 0.6, 0.9),
        "how far the moves of a step aside go, each in 16 directions",
        "m",
        minimum=0.05,
        maximum=10.0,
    ),
    # Holding short of a stream (stream_band.py): a robot that would enter the band people sweep without room
    # stops before it.
    Option(
        "stream_band_s",
        0.0,
        "the band people swept over this time and are forecast to sweep over it: a straight, avoiding or slow "
        "plan from outside the band that enters it with less than stream_band_entry_clearance_m from someone's "
        "forecast gives way to a stop short of it (0: off; 5 s is the measured value)",
        "s",
        minimum=0.0,
        maximum=30.0,
    ),
    Option(
        "stream_band_margin_m",
        0.3,
        "added to each person's checked radius for the band they sweep",
        "m",
        minimum=0.0,
        maximum=5.0,
    ),
    Option(
        "stream_band_entry_clearance_m",
        0.3,
        "clearance from everyone's forecast a plan keeps from the band's edge on (over 3 s) to enter the band",
        "m",
        minimum=0.0,
        maximum=5.0,
    ),
    # Speed (docs/explanation/speed.md).
    Option(
        "blocked_gap_m",
        0.3,
        "when static geometry closes the way (a closed door), the robot stops this far "
        "short of touching it (its margin included) and waits",
        "m",
        minimum=0.0,
        maximum=5.0,
    ),
    # Display.
    Option("record_candidates", False, "keep every candidate's polyline in the plan (for display)"),
]

# The planner's steps are compiled, one implementation each (viapath.jit): the option that chose between them and
# a numpy twin, and its former name, are read and ignored.
_ONE_ARITHMETIC = (
    "the planner's steps are compiled, one implementation each; viapath.jit runs them as plain Python when "
    "compilation is off"
)
VIAPATH_OPTIONS = COMMON_OPTIONS + OptionSet(
    _OWN,
    owner="viapath",
    steps=[("rollout_s", "rollout_dt_s"), ("escape_s", "escape_dt_s")],
    retired=[Retired("compute", _ONE_ARITHMETIC), Retired("backend", _ONE_ARITHMETIC)],
)
