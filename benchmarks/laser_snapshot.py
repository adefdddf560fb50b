"""Exact record of laser-perception episodes, to show that a change to the laser loop changes nothing.

    python benchmarks/laser_snapshot.py save before.pkl     # on the old code (PYTHONPATH)
    python benchmarks/laser_snapshot.py save after.pkl      # on the new code
    python benchmarks/laser_snapshot.py compare before.pkl after.pkl

``save`` runs paper ×12, eth-ucy ×6 (needs ``VIAPATH_DATA``) and crowd ×4 with laser perception,
planners viapath and dwa, seed 0, and keeps per episode: the metrics (wall-clock ones dropped),
robot poses, commands, plan status, the reported tracks of every cycle (positions, velocities,
radii, ids) and the scan points. ``compare`` prints how many episodes are bit-identical and the
largest absolute difference; exit code 1 if any differ.
"""

from __future__ import annotations

import pickle
import sys

import numpy as np

WALL_CLOCK = ("plan_time", "perception_time", "wall")


def save(path: str) -> int:
    from viapath.bench.suites import generate_suite
    from viapath.scenarios.models import Scenario
    from viapath.sim.loop import run_episode

    out = {}
    for suite, count in (("paper", 12), ("eth-ucy", 6), ("crowd", 4)):
        for data in generate_suite(suite, count, 0):
            scenario = Scenario.model_validate(data)
            for planner in ("viapath", "dwa"):
                episode = run_episode(scenario, planner=planner, perception="laser", seed=0, record_perceived=True)
                trace = episode.trace
                out[f"{scenario.name}/{planner}"] = dict(
                    metrics={k: v for k, v in episode.metrics.items() if not any(w in k for w in WALL_CLOCK)},
                    poses=trace.robot_poses.copy(),
                    commands=trace.commands.copy(),
                    status=list(trace.plan_status),
                    perceived=[
                        (o.positions.copy(), o.velocities.copy(), o.radii_m.copy(), np.asarray(o.ids).copy())
                        for o in trace.perceived
                    ],
                    scan_points=[np.asarray(p).copy() for p in trace.scan_points],
                )
    with open(path, "wb") as handle:
        pickle.dump(out, handle)
    print(f"{len(out)} episodes saved to {path}")
    return 0


def compare(before_path: str, after_path: str) -> int:
    with open(before_path, "rb") as handle:
        before = pickle.load(handle)
    with open(after_path, "rb") as handle:
        after = pickle.load(handle)
    if before.keys() != after.keys():
        print("different episodes:", sorted(set(before) ^ set(after))[:10])
        return 1
    largest, identical, notes = 0.0, 0, []

    def same(x, y, what) -> bool:
        nonlocal largest
        x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
        if x.shape != y.shape:
            notes.append(f"{what}: shape {x.shape} -> {y.shape}")
            return False
        if np.array_equal(x, y, equal_nan=True):
            return True
        largest = max(largest, float(np.nanmax(np.abs(x - y))))
        notes.append(f"{what}: differs")
        return False

    for key in before:
        a, b = before[key], after[key]
        ok = a["metrics"].keys() == b["metrics"].keys() and all(
            a["metrics"][m] == b["metrics"][m]
            or (a["metrics"][m] != a["metrics"][m] and b["metrics"][m] != b["metrics"][m])
            for m in a["metrics"]
        )
        if not ok:
            notes.append(f"{key}: metrics differ")
        ok &= same(a["poses"], b["poses"], f"{key} poses") & same(a["commands"], b["commands"], f"{key} commands")
        ok &= a["status"] == b["status"] and len(a["perceived"]) == len(b["perceived"])
        for i, (pa, pb) in enumerate(zip(a["perceived"], b["perceived"])):
            ok &= all([same(pa[j], pb[j], f"{key} tracks[{i}][{j}]") for j in range(4)])  # noqa: C419 -- a list: every difference is reported
        for i, (pa, pb) in enumerate(zip(a["scan_points"], b["scan_points"])):
            ok &= same(pa, pb, f"{key} scan[{i}]")
        identical += bool(ok)
    print(f"{identical}/{len(before)} episodes bit-identical; largest absolute difference {largest:.3g}")
    for note in notes[:20]:
        print(" ", note)
    return 0 if identical == len(before) else 1


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) == 2 and argv[0] == "save":
        return save(argv[1])
    if len(argv) == 3 and argv[0] == "compare":
        return compare(argv[1], argv[2])
    print(__doc__)
    return 2


if __name__ == "__main__":
    sys.exit(main())
