"""Which arithmetic the viapath planner runs: the numpy reference or the compiled kernels (extra ``fast``).

Source: a compiled hot path, the numpy path staying the reference; docs/speed.md.

* Option ``backend`` (:mod:`.options`): ``auto`` (default) uses numba when it is importable, ``numpy``
  and ``numba`` force one (``numba`` without numba installed is an error naming the extra). The
  environment variable ``VIAPATH_PLANNER_BACKEND`` (same choices) overrides ``auto`` only, so a
  whole benchmark can be run on the reference path without touching its scenario files.
* A :class:`Backend` holds the hot functions, :meth:`legs_first_contact` (leg-against-people
  checks), :meth:`via_options` (via points of (node, obstacle) pairs), :meth:`legs_inside` and
  :meth:`goal_legs_inside` (corridor checks), :meth:`goal_legs` (all of a batch of legs to the subgoal:
  contacts and corridor in one call), :meth:`grow` (the whole candidate tree), :meth:`track` (motion-limit roll-outs) and, for the
  escape, :meth:`escape` (the whole step in two calls) or, before the whole-step kernels are compiled,
  :meth:`corridor_excess` and :meth:`escape_contacts`, with the numpy signatures; the compiled ones get
  C-contiguous float64 arrays. The planner says in ``plan.extras["backend"]`` which one ran.
"""

from __future__ import annotations

import importlib.util
import os
from dataclasses import dataclass

import numpy as np

from viapath.geometry import legs_first_contact as numpy_legs_first_contact
from viapath.geometry import via_options as numpy_via_options
from viapath.kinematics import UnicycleState
from viapath.kinematics import track as numpy_track
from viapath.observation import MotionLimits

BACKENDS = ("auto", "numpy", "numba")
ENVIRONMENT_VARIABLE = "VIAPATH_PLANNER_BACKEND"


def numba_available() -> bool:
    return importlib.util.find_spec("numba") is not None


def resolve(choice: str) -> str:
    """``numpy`` or ``numba`` for an option value (``auto`` looks at the environment, then at numba)."""
    if choice == "auto":
        override = os.environ.get(ENVIRONMENT_VARIABLE, "").strip().lower()
        if override and override != "auto":
            if override not in BACKENDS:
                raise ValueError(
                    f"environment variable {ENVIRONMENT_VARIABLE}={override!r}: expected one of {', '.join(BACKENDS)}"
                )
            choice = override
        else:
            return "numba" if numba_available() else "numpy"
    if choice == "numba" and not numba_available():
        raise ValueError(
            "viapath option backend='numba' needs numba: install the extra 'fast' (pip install 'viapath[fast]')"
        )
    if choice not in ("numpy", "numba"):
        raise ValueError(f"viapath option backend={choice!r}: expected one of {', '.join(BACKENDS)}")
    return choice


@dataclass(frozen=True)
class Backend:
    name: str  # numpy | numba
    # numba: also the kernels that take over whole steps of the cycle (goal_legs, the candidate tree grow, the
    # choice, the escape).
    # They take seconds to compile the first time, so ``auto`` uses them only once they are in numba's cache
    # (:func:`compile_kernels`, which ``viapath bench`` and the ROS 2 node call before they start); until then
    # the smaller kernels do those steps, with the same decisions.
    whole_steps: bool = True

    def legs_first_contact(
        self,
        starts,
        start_times,
        velocities,
        durations,
        positions,
        velocities_obs,
        radii,
        growth,
        growth_until_s,
        leg_radii_m=None,
    ) -> np.ndarray:
        if self.name == "numpy":
            return numpy_legs_first_contact(
                starts,
                start_times,
                velocities,
                durations,
                positions,
                velocities_obs,
                radii,
                growth,
                growth_until_s,
                leg_radii_m,
            )
        from viapath.planning.viapath import kernels

        n = len(positions)
        legs = np.zeros(len(starts)) if leg_radii_m is None else _c(leg_radii_m)
        return kernels.legs_first_contact(
            _c(starts),
            _c(start_times),
            _c(velocities),
            _c(durations),
            _c(positions),
            _c(velocities_obs),
            _per_obstacle(radii, n),
            _per_obstacle(growth, n),
            _per_obstacle(growth_until_s, n),
            legs,
        )

    def via_options(
        self,
        starts,
        start_times,
        speeds,
        positions,
        velocities,
        via_radii,
        growth,
        growth_until_s,
        envelope_m,
        max_time_s,
    ):
        if self.name == "numpy":
            return numpy_via_options(
                starts,
                start_times,
                speeds,
                positions,
                velocities,
                via_radii,
                growth,
                growth_until_s,
                envelope_m,
                max_time_s,
            )
        from viapath.planning.viapath import kernels

        n = len(starts)
        return kernels.via_options(
            _c(starts),
            _c(start_times),
            _c(speeds),
            _c(positions),
            _c(velocities),
            _per_obstacle(via_radii, n),
            _per_obstacle(growth, n),
            _per_obstacle(growth_until_s, n),
            _per_obstacle(envelope_m, n),
            float(max_time_s),
        )

    def legs_inside(self, path, starts, ends, spacing_m: float, tolerance_m: float) -> np.ndarray:
        if self.name == "numpy":
            return path.legs_inside(starts, ends, spacing_m, tolerance_m)
        from viapath.planning.viapath import kernels

        return kernels.legs_inside(
            *_corridor(path),
            _c(np.reshape(starts, (-1, 2))),
            _c(np.reshape(ends, (-1, 2))),
            float(spacing_m),
            float(tolerance_m),
        )

    def goal_legs_inside(
        self, path, starts, subgoal, subgoal_index: int, spacing_m: float, tolerance_m: float
    ) -> np.ndarray | None:
        """None on the numpy path (the caller's own code is the reference)."""
        if self.name == "numpy":
            return None
        from viapath.planning.viapath import kernels

        inside = kernels.goal_legs_inside(*_corridor(path), _c(starts), int(subgoal_index), float(tolerance_m))
        if not inside.all():
            rest = np.flatnonzero(~inside)
            inside[rest] = kernels.legs_inside(
                *_corridor(path),
                _c(starts[rest]),
                _c(np.broadcast_to(subgoal, (len(rest), 2))),
                float(spacing_m),
                float(tolerance_m),
            )
        return inside

    def goal_legs(self, checks, starts, start_times, speeds, horizon_s: float):
        """:meth:`.checks.LegChecks.goal_legs` in one compiled call; None on the numpy path (the caller's own
        code is the reference)."""
        if self.name == "numpy" or not self.whole_steps:
            return None
        from viapath.planning.viapath import kernels

        obstacles = checks.kernel_obstacles()
        return kernels.goal_legs(
            _c(starts),
            _c(start_times),
            _c(speeds),
            _c(checks.subgoal),
            float(checks.stop_short_m),
            float(horizon_s),
            checks.kernel_continuation(),
            *obstacles,
            checks.kernel_envelope(),
            *_corridor(checks.path),
            int(checks.subgoal_index),
            float(checks.corridor_check_spacing_m),
            float(checks.corridor_tolerance_m),
        )

    def grow(self, checks, slow_checks, roots, config):
        """:func:`.candidates.grow`'s whole candidate tree in one compiled call: the node store (floats
        (M, 10), integers (M, 5), columns as in :mod:`.kernels`); None on the numpy path (the reference)."""
        if self.name == "numpy" or not self.whole_steps:
            return None
        from viapath.planning.viapath import kernels

        positions, velocities, radii, growth, until = checks.kernel_obstacles()
        _, _, slow_radii, slow_growth, slow_until = slow_checks.kernel_obstacles()
        path = checks.path
        index = int(checks.subgoal_index)
        # The robot's segment matters only when a corner can lie between it and the subgoal.
        segment = int(path.project(checks.position)[0]) if index >= 2 else 0
        slow_times = np.asarray(config.slow_times_s, dtype=np.float64).reshape(-1)
        return kernels.grow(
            _c(checks.position),
            _c(checks.subgoal),
            _c(roots.speeds),
            int(roots.nominal_index),
            _c(roots.directions),
            _c(roots.lengths),
            np.ascontiguousarray(roots.free, dtype=np.bool_),
            _c(roots.contact),
            positions,
            velocities,
            radii,
            growth,
            until,
            _per_obstacle(checks.via_radii, len(positions)),
            np.ascontiguousarray(checks.obstacles.ids, dtype=np.int64),
            slow_radii,
            slow_growth,
            slow_until,
            slow_times,
            bool(len(slow_times)),
            float(checks.stop_short_m),
            float(checks.horizon_s),
            checks.kernel_continuation(),
            checks.kernel_envelope(),
            *_corridor(path),
            _c(path.waypoints),
            segment,
            index,
            float(checks.corridor_check_spacing_m),
            float(checks.corridor_tolerance_m),
            int(config.max_depth),
            int(config.max_root_obstacles),
        )

    def choose(self, checks, slow_checks, speeds, slow_times: np.ndarray, settings: np.ndarray, integers: np.ndarray):
        """The planner's choice up to its shield check in one compiled call (roots, step 1, the candidate tree,
        Eq. 1's critics, the order and the roll-outs up to the first candidate that follows):
        :func:`.kernels.choose`; None on the numpy path. ``slow_times`` (float64), ``settings`` and ``integers``
        are the kernel's, filled in by the planner."""
        if self.name == "numpy" or not self.whole_steps:
            return None
        (
            robot,
            positions,
            velocities,
            radii,
            growth,
            until,
            via_radii,
            ids,
            continuation,
            envelope,
            starts,
            directions,
            lengths,
            half_widths,
            waypoints,
        ) = checks.kernel_choice_inputs()
        _, _, slow_radii, slow_growth, slow_until = (
            (positions, velocities, radii, growth, until) if slow_checks is checks else slow_checks.kernel_obstacles()
        )
        return _kernels().choose(
            robot,
            _c(speeds),
            _c(checks.subgoal),
            positions,
            velocities,
            radii,
            growth,
            until,
            via_radii,
            ids,
            slow_radii,
            slow_growth,
            slow_until,
            slow_times,
            continuation,
            envelope,
            starts,
            directions,
            lengths,
            half_widths,
            waypoints,
            settings,
            integers,
        )

    def corridor_excess(self, path, points) -> np.ndarray:
        if self.name == "numpy":
            return path.corridor_excess(points)
        from viapath.planning.viapath import kernels

        return kernels.corridor_excess(*_corridor(path), _c(points))

    def escape_contacts(
        self,
        positions,
        times,
        positions_obs,
        velocities_obs,
        check_radii,
        growth,
        growth_until_s,
        overlapping,
        steps: int,
    ):
        """First contact step (K,) and the gaps to the people overlapped now (smallest, last: (K, M)) of
        K roll-outs; None on the numpy path (:func:`.escape.escape_scores` is the reference)."""
        if self.name == "numpy":
            return None
        from viapath.planning.viapath import kernels

        return kernels.escape_contacts(
            _c(positions),
            _c(times),
            _c(positions_obs),
            _c(velocities_obs),
            _c(check_radii),
            _c(growth),
            _c(growth_until_s),
            np.ascontiguousarray(overlapping, dtype=np.bool_),
            int(steps),
        )

    def escape(self, checks, limits: MotionLimits, config, fan, previous=None, score_standing: bool = False):
        """:func:`.escape.stop_or_escape`'s figures in two compiled calls: :func:`.kernels.escape_headings` (the
        standing check, the fan's headings), numpy's sines and cosines of those headings (as
        :func:`viapath.kinematics.rollout` takes them), :func:`.kernels.escape_scores`. Returns (standing is
        free, commands (K, 2), ends (K, 2), scores (K,)), the last three None when standing is free (unless
        ``score_standing``); None on the numpy path and before the whole-step kernels are compiled (then
        :func:`.escape.escape_scores`, the reference, runs with the smaller kernels). ``fan``:
        :func:`.escape.escape_fan`'s (top speed, commands, distinct turn commands, each command's turn)."""
        if self.name == "numpy" or not self.whole_steps:
            return None
        kernels = _kernels()
        top, commands, row_turns, turn_rows = fan
        dt = config.escape_dt_s
        steps = max(1, int(round(config.escape_s / dt)))
        calm = bool(config.calm_escape and previous is not None)
        settings = np.array(
            [
                dt,
                config.escape_s,
                limits.max_accel_mps2 * dt,
                limits.max_turn_accel_radps2 * dt,
                limits.max_speed_mps,
                limits.max_turn_rate_radps,
                checks.corridor_tolerance_m,
                max(config.escape_max_excess_m, checks.corridor_tolerance_m),
                max(top, 1e-9),
                config.escape_continuity_s if calm else 0.0,
                previous.speed_mps if calm else 0.0,
                previous.turn_rate_radps if calm else 0.0,
                checks.horizon_s,
                config.horizon_s,
            ],
            dtype=np.float64,
        )
        robot = checks.kernel_robot()
        obstacles = checks.kernel_obstacles()
        standing_free, headings = kernels.escape_headings(robot, *obstacles, row_turns, settings, steps)
        if standing_free and not score_standing:
            return True, None, None, None
        ends, score = kernels.escape_scores(
            robot,
            commands,
            turn_rows,
            np.sin(headings),
            np.cos(headings),
            *obstacles,
            *_corridor(checks.path),
            _c(checks.subgoal),
            settings,
            steps,
            calm,
        )
        return standing_free, commands, ends, score

    def track(
        self,
        state: UnicycleState,
        target,
        speed_mps: float,
        limits: MotionLimits,
        dt_s: float,
        steps: int,
        heading_gain: float,
    ) -> np.ndarray:
        if self.name == "numpy":
            return numpy_track(state, target, speed_mps, limits, dt_s, steps, heading_gain)
        from viapath.planning.viapath import kernels

        return kernels.track(
            float(state.x),
            float(state.y),
            float(state.heading_rad),
            float(state.speed_mps),
            float(state.turn_rate_radps),
            float(target[0]),
            float(target[1]),
            float(speed_mps),
            float(limits.max_speed_mps),
            float(limits.max_turn_rate_radps),
            float(limits.max_accel_mps2),
            float(limits.max_turn_accel_radps2),
            float(dt_s),
            int(steps),
            float(heading_gain),
        )


def _kernels():
    """The kernels module (imports numba: only on the compiled path; kept after the first import, as the
    per-call import statement costs a microsecond)."""
    global _KERNELS
    if _KERNELS is None:
        from viapath.planning.viapath import kernels

        _KERNELS = kernels
    return _KERNELS


_KERNELS = None


def _c(array) -> np.ndarray:
    return np.ascontiguousarray(array, dtype=np.float64)


def _corridor(path):
    """The path's segment arrays, C-contiguous float64 (cached on the path object)."""
    arrays = getattr(path, "_kernel_arrays", None)
    if arrays is None:
        arrays = (
            _c(path.segment_starts),
            _c(path.segment_directions),
            _c(path.segment_lengths_m),
            _c(path.half_widths_m),
        )
        path._kernel_arrays = arrays
    return arrays


def _per_obstacle(values, n: int) -> np.ndarray:
    """One float64 per obstacle (a scalar is repeated)."""
    if isinstance(values, np.ndarray) and values.shape == (n,):
        return _c(values)
    return np.full(n, values, dtype=np.float64) if np.ndim(values) == 0 else _c(np.broadcast_to(values, (n,)))


NUMPY = Backend("numpy")


def backend_for(choice: str) -> Backend:
    name = resolve(choice)
    explicit = choice != "auto" or os.environ.get(ENVIRONMENT_VARIABLE, "").strip().lower() not in ("", "auto")
    return Backend(name, whole_steps=name == "numba" and (explicit or whole_steps_compiled()))


def whole_steps_compiled() -> bool:
    """Whether the kernels of whole steps (goal_legs, grow, the choice, the escape) cost no compilation now:
    compiled in this process or in numba's on-disk cache."""
    from viapath.planning.viapath import kernels

    for kernel in (kernels.goal_legs, kernels.grow, kernels.choose, kernels.escape_headings, kernels.escape_scores):
        if kernel.signatures:
            continue
        cache_file = getattr(getattr(kernel, "_cache", None), "_cache_file", None)
        index = getattr(cache_file, "_index_path", None)
        if index is None or not os.path.exists(index):
            return False
    return True


def compile_kernels() -> bool:
    """Compile every planner kernel now if numba is there and the whole-step ones are not compiled yet
    (about 30 s of CPU once per machine, the choice kernel most of it: numba caches them on disk); True
    when they are ready. Two planning cycles run all of them with the planner's own argument types: one whose
    straight leg is blocked (goal_legs and grow inside the choice kernels), one closed in from four sides,
    where no candidate is free and standing is hit too (the escape's kernels)."""
    if not numba_available():
        return False
    if not whole_steps_compiled():
        from viapath.observation import Observation, RobotState
        from viapath.path import DesignatedPath
        from viapath.planning import make_planner

        planner = make_planner(
            "viapath",
            DesignatedPath([[0.0, 0.0], [6.0, 0.0]], half_width_m=1.0),
            nominal_speed_mps=0.2,
            backend="numba",
        )
        for people in warm_up_crowds():
            planner.reset()
            planner.plan(Observation(0.0, RobotState(np.zeros(2), 0.0, 0.2, 0.0, 0.25), people))
    return True


def warm_up_crowds() -> list:
    """:func:`compile_kernels`' people: one walking at the robot along the path (the choice), four closing in
    on it from all sides (the escape; tests/planning/test_backends.py checks that both cycles get there)."""
    from viapath.observation import Obstacles

    sides = np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])
    return [
        Obstacles(np.array([[2.0, 0.0]]), np.array([[-0.2, 0.0]]), np.array([0.3])),
        Obstacles(0.9 * sides, -0.3 * sides, np.full(4, 0.3)),
    ]


#: The compiled backend without its whole-step kernels (the recipe's steps in numpy, their leg checks and via
#: points compiled): what a cycle with static geometry runs on (planner._cycle_backend).
STEPWISE = {"numba": Backend("numba", whole_steps=False)}
