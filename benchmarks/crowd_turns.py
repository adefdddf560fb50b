"""Why a generated crowd person walks into a robot at rest: what turned them, in the generator's own terms.

Usage: python benchmarks/crowd_turns.py OUT [OUT ...] [--workers 2] [--options JSON] [--detail] [--json]

Each OUT is a ``viapath bench`` results folder of a suite with the social-force families (``mixed``, ``crowd``,
``hallway``). Every crowd or hallway episode with a contact is run again (as benchmarks/classify_contacts.py
does; ``--options``: the planner options of the runs) and, for each contact that began with the robot at rest
(viapath.bench.contact_kinds), the scenario's crowd is simulated again from the generator's own inputs
(viapath.bench.suites, the same seed and index) to tell:

* **What turned them** over the 2 s before the onset: the social-force terms (viapath.sim.social_force)
  evaluated on the simulated states every 0.1 s and integrated — the driving term (towards the person's current
  waypoint), the other people's repulsion and the walls' — each as the velocity change it made across the
  person's heading at the start of the window (m/s; the person's own change is printed beside). A turn the
  repulsion makes is a person stepping round another person; the driving term turns them when they
  reach a waypoint or after a push.
* **Whether a robot the crowd could see would have been touched**: the same crowd simulated again with one
  more standing person of the robot's radius where the robot stood at the onset, there from the start (the
  crowd treats it as it treats anyone standing); the contact is **avoided** when the person's path then
  keeps clear of that spot from 3 s before the onset to 3 s after. The robot's presence before it came to rest
  is not modelled: the counterfactual is "people who see a standing robot", not the episode rerun.

Nothing here changes the suite: it measures how the suite's people move.
"""

from __future__ import annotations

import argparse
import collections
import csv
import json
from pathlib import Path

import numpy as np
from joblib import Parallel, delayed

WINDOW_S = 2.0  # the window before the onset whose turn is explained
CLEAR_WINDOW_S = 3.0  # the counterfactual contact is looked for this long either side of the onset


def _generator_inputs(name: str, seed: int) -> dict:
    """The social-force call the generator makes for scenario ``name`` (family-index) of a suite seed."""
    from viapath.bench import suites

    family, index = name.rsplit("-", 1)
    index = int(index)
    captured: dict = {}
    real = suites.simulate_crowd

    def capture(starts, routes, speeds, duration_s, **kwargs):
        captured.update(starts=starts, routes=routes, speeds=speeds, duration_s=duration_s, **kwargs)
        return real(starts, routes, speeds, duration_s, **kwargs)

    suites.simulate_crowd = capture
    try:
        family_index = index // len(suites.SYNTHETIC_FAMILIES) if family in suites.SYNTHETIC_FAMILIES else index
        suites.FAMILIES.get(family)(np.random.default_rng([seed, index]), family_index)
    finally:
        suites.simulate_crowd = real
    return captured


def simulate(inputs: dict, standing_at: np.ndarray | None = None):
    """The generator's crowd again, sampled at every step of the simulator (the generator keeps every second
    step: the same integration), with one more person standing at ``standing_at`` (radius 0.25 m) if given."""
    from viapath.sim.social_force import SocialForceParams, simulate_crowd

    n = len(inputs["starts"])
    starts = np.asarray(inputs["starts"], float).reshape(-1, 2).tolist()
    routes, speeds = list(inputs["routes"]), np.broadcast_to(np.asarray(inputs["speeds"], float), (n,)).tolist()
    times = np.broadcast_to(
        np.asarray(inputs.get("start_times_s", 0.0) if inputs.get("start_times_s") is not None else 0.0, float), (n,)
    ).tolist()
    if standing_at is not None:
        starts, routes = [*starts, standing_at.tolist()], [*routes, [standing_at.tolist()]]
        speeds, times = [*speeds, 0.0], [*times, 0.0]
    step_s = SocialForceParams().step_s
    return simulate_crowd(
        starts, routes, speeds, inputs["duration_s"], sample_dt_s=step_s, walls=inputs.get("walls"), start_times_s=times
    )


def _current_goals(positions: np.ndarray, routes: list, reach_m: float) -> np.ndarray:
    """(T, N, 2) the waypoint each person heads for at each sample (the route advances within ``reach_m``)."""
    goals = np.zeros_like(positions)
    for j, route in enumerate(routes):
        route = np.asarray(route, dtype=float).reshape(-1, 2)
        k = 0
        for t in range(len(positions)):
            while k < len(route) - 1 and np.hypot(*(route[k] - positions[t, j])) < reach_m:
                k += 1
            goals[t, j] = route[k]
    return goals


def force_split(inputs: dict, trajectory, person: int, onset_s: float) -> dict:
    """The velocity change across the person's heading over the window before ``onset_s``, per social-force term."""
    from viapath.forecast import elliptic_repulsion
    from viapath.sim.social_force import SocialForceParams, _wall_forces

    params = SocialForceParams()
    dt = float(trajectory.times_s[1] - trajectory.times_s[0])
    end = int(round(onset_s / dt))
    start = max(end - int(round(WINDOW_S / dt)), 0)
    p, v = trajectory.positions, trajectory.velocities
    heading = v[start, person] / max(float(np.hypot(*v[start, person])), 1e-9)
    across = np.array([-heading[1], heading[0]])
    goals = _current_goals(p[: end + 1], inputs["routes"], params.reach_m)
    desired = np.broadcast_to(np.asarray(inputs["speeds"], float), (p.shape[1],))[person]
    walls = np.asarray(inputs.get("walls") if inputs.get("walls") is not None else np.zeros((0, 2, 2)), float)
    split = {"drive": 0.0, "people": 0.0, "walls": 0.0, "peak_push_mps2": 0.0, "nearest_at_peak_m": np.inf}
    pusher: collections.Counter = collections.Counter()
    radii = np.full(p.shape[1], 0.25)
    for t in range(start, end + 1):  # the trapezoid rule over the samples
        weight = dt * (0.5 if t in (start, end) else 1.0)
        to_goal = goals[t, person] - p[t, person]
        drive = (desired * to_goal / max(float(np.hypot(*to_goal)), 1e-9) - v[t, person]) / params.relaxation_time_s
        pair = elliptic_repulsion(
            p[t],
            v[t],
            radii[:, None] + radii[None, :],
            (params.agent_strength_m2ps2, params.agent_range_m, params.step_time_s),
            (params.field_of_view_rad, params.outside_view_weight),
        )[person]
        for other in range(p.shape[1]):  # who pushed: each other person's share alone
            if other != person:
                two = [person, other]
                alone = elliptic_repulsion(
                    p[t, two],
                    v[t, two],
                    0.5,
                    (params.agent_strength_m2ps2, params.agent_range_m, params.step_time_s),
                    (params.field_of_view_rad, params.outside_view_weight),
                )[0]
                pusher[other] += abs(float(alone @ across)) * weight
        if float(np.hypot(*pair)) > split["peak_push_mps2"]:
            others = np.hypot(*(p[t] - p[t, person]).T)
            others[person] = np.inf
            split["peak_push_mps2"] = float(np.hypot(*pair))
            split["nearest_at_peak_m"] = float(others.min())
        wall = _wall_forces(p[t, person][None], walls, params)[0]
        split["drive"] += float(drive @ across) * weight
        split["people"] += float(pair @ across) * weight
        split["walls"] += float(wall @ across) * weight
    split["peak_accel_mps2"] = float(np.max(np.hypot(*np.diff(v[start : end + 1, person], axis=0).T)) / dt)
    split["actual"] = float((v[end, person] - v[start, person]) @ across)
    v0, v1 = v[start, person], v[end, person]
    turn = np.degrees(np.arctan2(v0[0] * v1[1] - v0[1] * v1[0], v0 @ v1))
    split["turn_deg"] = float(abs(turn))
    split["pushed_by"] = int(pusher.most_common(1)[0][0]) if pusher else -1
    return split


def seen_robot_gap(inputs: dict, person: int, robot_xy: np.ndarray, onset_s: float) -> float:
    """The person's least gap to a standing robot at ``robot_xy`` that the crowd sees (robot radius 0.25 m),
    over the onset ± CLEAR_WINDOW_S (negative: they touch)."""
    trajectory = simulate(inputs, robot_xy)
    dt = float(trajectory.times_s[1] - trajectory.times_s[0])
    a = max(int(round((onset_s - CLEAR_WINDOW_S) / dt)), 0)
    b = int(round((onset_s + CLEAR_WINDOW_S) / dt)) + 1
    track = trajectory.positions[a:b, person]
    return float(np.min(np.hypot(*(track - robot_xy[None]).T)) - 0.5)


def _off_polyline(point: np.ndarray, polyline: np.ndarray) -> float:
    """The distance from ``point`` to the polyline (the person's straight route: start, then each waypoint)."""
    best = np.inf
    for a, b in zip(polyline[:-1], polyline[1:]):
        along = float(np.clip((point - a) @ (b - a) / max(float((b - a) @ (b - a)), 1e-12), 0.0, 1.0))
        best = min(best, float(np.hypot(*(point - a - along * (b - a)))))
    return best


def _suite_seed(yaml_path: str) -> int:
    """The suite seed the generator drew the scenario with (the YAML's ``seed``; the episodes' own seed differs)."""
    import yaml

    with open(yaml_path) as file:
        return int(yaml.safe_load(file)["seed"])


def _episode(yaml_path: str, name: str, seed: int, perception: str, options: dict | None) -> list[dict]:
    from viapath.bench.contact_kinds import contact_kinds
    from viapath.scenarios.loader import load_scenario
    from viapath.sim.loop import run_episode

    scenario = load_scenario(yaml_path)
    trace = run_episode(scenario, seed=seed, perception=perception, planner_overrides=options).trace
    out = []
    inputs = None
    for contact in contact_kinds(trace):
        if not contact.at_rest:
            continue
        if inputs is None:
            inputs = _generator_inputs(name, _suite_seed(yaml_path))
            trajectory = simulate(inputs)
        step = int(round(contact.time_s / trace.dt_s))
        robot_xy = trace.robot_poses[step, :2].copy()
        moving = np.flatnonzero(trace.robot_speeds_mps[: step + 1] > 0.005)
        rest_s = contact.time_s - (float(trace.times_s[moving[-1]]) if len(moving) else 0.0)
        split = force_split(inputs, trajectory, contact.person, contact.time_s)
        gap = seen_robot_gap(inputs, contact.person, robot_xy, contact.time_s)
        route = np.vstack([np.asarray(inputs["starts"], float)[contact.person], inputs["routes"][contact.person]])
        out.append(
            {
                "scenario": name,
                "time_s": contact.time_s,
                "person": contact.person,
                "kind": contact.kind,
                "at_rest_s": rest_s,
                **split,
                "seen_robot_gap_m": gap,
                "off_route_m": _off_polyline(robot_xy, route),
            }
        )
    return out


def base_rate(folders: list[Path]) -> tuple[int, int, int]:
    """Over every crowd and hallway scenario of the folders' suites: the 2 s windows of a person moving at its end
    (faster than 0.1 m/s), and how many of them hold an acceleration harder than 1 and 2 m/s² (differences of
    the generator's own states, every 0.05 s): the same figure as the contacts' peak acceleration, for any moment."""

    moving = over_1 = over_2 = 0
    for folder in folders:
        for path in sorted((folder / "suite").glob("*.yaml")):
            if path.stem.rsplit("-", 1)[0] not in ("crowd", "hallway"):
                continue
            trajectory = simulate(_generator_inputs(path.stem, _suite_seed(str(path))))
            dt = float(trajectory.times_s[1] - trajectory.times_s[0])
            v = trajectory.velocities
            accel = np.hypot(*np.moveaxis(np.diff(v, axis=0), -1, 0)) / dt  # (T - 1, N)
            width = int(round(WINDOW_S / dt))
            if len(accel) < width:
                continue
            peak = np.lib.stride_tricks.sliding_window_view(accel, width, axis=0).max(axis=-1)  # window ending at k
            on = np.hypot(*np.moveaxis(v[width:], -1, 0)) > 0.1
            moving += int(on.sum())
            over_1 += int((on & (peak > 1.0)).sum())
            over_2 += int((on & (peak > 2.0)).sum())
    return moving, over_1, over_2


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folders", nargs="+", type=Path)
    parser.add_argument("--workers", "-w", type=int, default=2)
    parser.add_argument("--options", type=json.loads, default=None)
    parser.add_argument("--detail", action="store_true")
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--base-rate", action="store_true", help="also: how often the whole crowd accelerates hard")
    args = parser.parse_args()
    jobs = []
    for folder in args.folders:
        with open(folder / "episodes.csv", newline="") as file:
            rows = [r for r in csv.DictReader(file) if r["planner"] == "viapath" and r["collision"] == "True"]
        jobs += [(folder, r) for r in rows if r["family"] in ("crowd", "hallway")]
    done = Parallel(n_jobs=args.workers)(
        delayed(_episode)(
            str(f / "suite" / f"{r['scenario']}.yaml"), r["scenario"], int(r["seed"]), r["perception"], args.options
        )
        for f, r in jobs
    )
    records = [c for part in done for c in part]
    if args.json:
        print(json.dumps(records, indent=1))
        return
    if args.detail:
        for r in records:
            print(
                f"{r['scenario']} t={r['time_s']:.1f}s person {r['person']} {r['kind']}: at rest {r['at_rest_s']:.1f}"
                f" s, turn {r['turn_deg']:.0f}°, across-heading Δv {r['actual']:+.2f} m/s = drive "
                f"{r['drive']:+.2f} + people {r['people']:+.2f} + walls {r['walls']:+.2f} (pushed most by "
                f"{r['pushed_by']}); peak acceleration {r['peak_accel_mps2']:.1f} m/s², peak push {r['peak_push_mps2']:.1f} m/s²"
                f" with the nearest person {r['nearest_at_peak_m']:.2f} m away; robot {r['off_route_m']:.2f} m off their"
                f" route; robot seen: gap "
                f"{r['seen_robot_gap_m']:+.2f} m"
            )
    summarise(records)
    if args.base_rate:
        moving, over_1, over_2 = base_rate(args.folders)
        print(
            f"base rate, every crowd/hallway person of these suites: of {moving} 2 s windows of a moving person, "
            f"{100 * over_1 / max(moving, 1):.1f} % hold an acceleration above 1 m/s², {100 * over_2 / max(moving, 1):.1f} %"
            " above 2 m/s²"
        )


def summarise(records: list[dict]) -> None:
    n = len(records)
    turned = [r for r in records if r["turn_deg"] >= 15.0]
    by_people = [r for r in turned if abs(r["people"]) >= abs(r["drive"]) and abs(r["people"]) >= abs(r["walls"])]
    avoided = [r for r in records if r["seen_robot_gap_m"] > 0.0]
    for limit in (1.0, 2.0):
        hard = [r for r in records if r["peak_accel_mps2"] > limit]
        far = [r for r in hard if r["peak_push_mps2"] > limit and r["nearest_at_peak_m"] > 1.5]
        print(
            f"{len(hard)} of {n} accelerated harder than {limit:.0f} m/s² in the 2 s before the onset; in {len(far)}"
            f" of those other people pushed harder than that while nobody was within 1.5 m"
        )
    print(
        f"{n} contacts with the robot at rest in crowd/hallway episodes; median time at rest before the onset "
        f"{np.median([r['at_rest_s'] for r in records]) if n else float('nan'):.1f} s"
    )
    print(
        f"{len(turned)} of them turned >= 15° over the 2 s before; in {len(by_people)} of those the other "
        f"people's repulsion made the larger share of the velocity change across the heading"
    )
    on_route = [r for r in records if r["off_route_m"] < 0.5]
    print(
        f"{len(on_route)} of {n} had the robot standing within 0.5 m (the two radii) of the person's straight route"
        f" (start to waypoints): the robot stood on the line the person's driving term steers them back to"
    )
    print(
        f"{len(avoided)} of {n} would not have happened had the crowd seen the standing robot "
        f"(one more standing person there): least gap > 0 within ±{CLEAR_WINDOW_S:.0f} s of the onset"
    )


if __name__ == "__main__":
    main()
