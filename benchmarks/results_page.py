"""Write docs/results.md, the one page of measured figures, from the benchmark runs it names.

Usage:
    python benchmarks/results_page.py [--work out/results] [--workers 2] [--with peers,ros2,speed]
    python benchmarks/results_page.py --from DIR          # only read the outputs already in DIR
    python benchmarks/results_page.py --check             # exit 1 if docs/results.md differs from what DIR gives

Each measurement is one command whose output lands in the work folder under a fixed name (the table
below, ``RUNS``); the page shows every figure next to the command that printed it. Without ``--from``
the script runs the measurements that are missing from the folder (a rerun reuses what is there:
delete a file or folder to measure it again), then writes the page. With ``--from DIR`` it runs
nothing. A measurement without output (no data set, an extra not installed, not asked for) gets its
command and a note instead of figures; the ROS 2 table, whose runs need the ``ros2`` extra, is
carried over from the current page when the folder has none, so that the page never loses it.

The folder layout is the one of a plain shell run of the same commands, e.g.
``viapath bench mixed --count 200 --seed 0 -p viapath -w 2 --no-plots --out DIR/mixed0``, so outputs
made by hand (or by another script with these names) are read the same way.

Choices: counts and rates are the figures (they depend only on the seeds); wall-clock plan times are
left out of the tables (they depend on the machine and its load) and live in the optional speed
section, which prints the speed benchmarks' own tables as they print them.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "results.md"
PAPER = ("paper-behind", "paper-front", "paper-side")
PEERS = "viapath,follow,stop,dwa,vo,nav-orca,nav-hl,nav-hrvo,nav-sf"


@dataclass(frozen=True)
class Bench:
    """One ``viapath bench`` run: its output folder name under the work folder, and its arguments."""

    name: str
    suite: str
    count: int
    seed: int
    planners: str = "viapath"
    perception: str = "oracle"
    optional: str = ""  # the --with word that asks for it ("" = always run)

    def argv(self, out: Path, workers: int) -> list[str]:
        argv = ["bench", self.suite, "--count", str(self.count), "--seed", str(self.seed), "-p", self.planners]
        argv += ["-w", str(workers), "--no-plots", "--out", str(out / self.name)]
        return argv + (["--perception", self.perception] if self.perception != "oracle" else [])

    def shown(self, workers: int) -> str:
        return "viapath " + " ".join(self.argv(Path("OUT"), workers))


BENCHES = (
    Bench("mixed0", "mixed", 200, 0),
    Bench("mixed3", "mixed", 200, 3),
    Bench("eth7", "eth-ucy", 100, 7),
    Bench("static11", "static", 50, 11),
    Bench("static11laser", "static", 50, 11, perception="laser"),
    Bench("mixed0-peers", "mixed", 200, 0, planners=PEERS, optional="peers"),
)

#: Speed benchmarks (optional, ``--with speed``): output file, command; their printed tables are shown as they are.
SPEED = (
    ("speed-planner.txt", ["benchmarks/bench_planner.py"]),
    ("speed-laser-loop.txt", ["benchmarks/bench_laser_loop.py"]),
)
SCANS = "scans-positive2.json"  # viapath scans --json of the labelled leg_tracker recording
SCANS_BAG = "leg_tracker_laser/positive_2_extracted.bag"  # under the data folder ($VIAPATH_DATA)
ROS2_TABLE = "ros2-paper-table.md"
MACHINE = "machine.txt"  # what the runs ran on, written before the first run


def _cli(argv: list[str], stdout: Path | None = None) -> int:
    """Run ``viapath ARGV`` with this interpreter (so an uninstalled tree on PYTHONPATH works too)."""
    command = [sys.executable, "-m", "viapath.cli", *argv]
    print("+ viapath " + " ".join(argv), file=sys.stderr, flush=True)
    if stdout is None:
        return subprocess.call(command, cwd=ROOT)
    with open(stdout, "w") as out:
        return subprocess.call(command, cwd=ROOT, stdout=out)


def measure(work: Path, workers: int, extras: set[str]) -> None:
    """Run every measurement whose output is missing from ``work``."""
    work.mkdir(parents=True, exist_ok=True)
    if not (work / MACHINE).exists():
        (work / MACHINE).write_text(_machine() + "\n")
    for case in PAPER:
        for suffix, extra in (("", []), ("-laser", ["--perception", "laser"])):
            target = work / f"{case}{suffix}.json"
            if not target.exists() and _cli(["run", case, "--json", *extra], stdout=target.with_suffix(".tmp")) == 0:
                target.with_suffix(".tmp").replace(target)
    for bench in BENCHES:
        if bench.optional and bench.optional not in extras:
            continue
        if not (work / bench.name / "summary.json").exists():
            code = _cli(bench.argv(work, workers))
            if code not in (0, 3):  # 3: some episode crashed; the table says so
                print(
                    f"results_page: {bench.name}: viapath bench exited {code}; its section is left out", file=sys.stderr
                )
    if not (work / SCANS).exists():
        from viapath.bench.suites import data_root

        bag = data_root() / SCANS_BAG
        if (
            bag.exists()
            and _cli(["scans", str(bag), "--labels", "/leg_cluster_positions", "--json"], work / "scans.tmp") == 0
        ):
            (work / "scans.tmp").replace(work / SCANS)
    if "ros2" in extras and not (work / ROS2_TABLE).exists():
        _script(["benchmarks/ros2_paper_table.py"], work / ROS2_TABLE)
    if "speed" in extras:
        for name, argv in SPEED:
            if not (work / name).exists():
                _script(argv, work / name)


def _script(argv: list[str], target: Path) -> None:
    print("+ python " + " ".join(argv), file=sys.stderr, flush=True)
    result = subprocess.run([sys.executable, *argv], cwd=ROOT, capture_output=True, text=True)
    if result.returncode == 0 and result.stdout.strip():
        target.write_text(result.stdout)
    else:
        print(f"results_page: {' '.join(argv)} failed ({result.returncode}): {result.stderr[-500:]}", file=sys.stderr)


# --- reading ---------------------------------------------------------------------------------------


def _json(path: Path):
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return None


def _pct(x) -> str:
    return "–" if x is None else f"{100 * x:.1f} %"


def _num(x, fmt: str = ".2f") -> str:
    return "–" if x is None else format(x, fmt)


def paper_section(work: Path) -> list[str]:
    out = [
        "## The paper's three experiments",
        "",
        "The robot drives 5 m at 0.2 m/s in a corridor ±1 m wide; one person walks at 0.3 m/s from behind, "
        "head-on or across. Shield on (the default), once with exact knowledge of the person (oracle) and once "
        "with two simulated laser scanners and tracking.",
        "",
        "```bash",
        *(f"viapath run {c} --json{s}" for c in PAPER for s in ("", " --perception laser")),
        "```",
        "",
    ]
    rows = []
    for case in PAPER:
        for suffix, label in (("", "oracle"), ("-laser", "laser")):
            m = _json(work / f"{case}{suffix}.json")
            if m is None:
                continue
            rows.append(
                f"| {case} | {label} | {'yes' if m.get('reached_goal') else 'no'} | "
                f"{'yes' if m.get('collision') else 'no'} | {_num(m.get('min_clearance_m'))} | "
                f"{_num(m.get('time_to_goal_s'), '.1f')} | {_num(m.get('min_speed_mps'))} | "
                f"{_num(m.get('max_speed_mps'))} | {_num(m.get('max_lateral_deviation_m'))} | "
                f"{_num(m.get('time_outside_corridor_s'), '.1f')} | {m.get('shield_interventions', '–')} |"
            )
    if not rows:
        return [*out, "*Not measured in this run: run the commands above.*", ""]
    return [
        *out,
        "| scenario | perception | goal | contact | min clearance [m] | time to goal [s] | min speed [m/s] | "
        "max speed [m/s] | max lateral deviation [m] | outside corridor [s] | shield interventions |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
        *rows,
        "",
    ]


SUMMARY_HEAD = (
    "| run | planner | episodes | success | reached goal | contact | at fault | avoidable / unavoidable | static contact | "
    "time ratio (median) | mean lateral deviation [m] | outside corridor [s/episode] | min clearance [m] | "
    "shield interventions / episode | crashed |"
)


def _summary_rows(label: str, summary: list[dict]) -> list[str]:
    rows = []
    for s in summary:
        interventions = s.get("shield_interventions_per_episode")
        rows.append(
            f"| {label} | {s.get('planner')} | {s.get('episodes')} | {_pct(s.get('success_rate'))} | "
            f"{_pct(s.get('reached_goal_rate'))} | {_pct(s.get('collision_rate'))} | {_pct(s.get('at_fault_collision_rate'))} | "
            f"{s.get('at_fault_avoidable', '–')} / {s.get('at_fault_unavoidable', '–')} | "
            f"{_pct(s.get('static_contact_rate'))} | {_num(s.get('time_ratio_median'))} | "
            f"{_num(s.get('mean_lateral_deviation_m'), '.3f')} | {_num(s.get('time_outside_corridor_s'))} | "
            f"{_num(s.get('min_clearance_m'))} | {_num(interventions, '.1f') if interventions is not None else '–'} | "
            f"{s.get('errors', 0)} |"
        )
    return rows


def bench_section(work: Path, title: str, text: str, benches: list[tuple[str, Bench]], workers: int) -> list[str]:
    out = [f"## {title}", "", text, "", "```bash", *(b.shown(workers) for _, b in benches), "```", ""]
    rows: list[str] = []
    missing = []
    for label, bench in benches:
        summary = _json(work / bench.name / "summary.json")
        if summary is None:
            missing.append(label)
            continue
        rows += _summary_rows(label, summary)
    if rows:
        out += [SUMMARY_HEAD, _rule(SUMMARY_HEAD), *rows, ""]
    if missing:
        out += [f"*Not measured in this run: {', '.join(missing)}. Run the command above.*", ""]
    return out


def _rule(head: str) -> str:
    return "|" + "---|" * (head.count("|") - 1)


def scans_section(work: Path) -> list[str]:
    out = [
        "## Real scans",
        "",
        "The perception chain on a real recording with labelled leg positions (the `leg_tracker` data set, "
        "Leigh et al., ICRA 2015; not in the repository: `$VIAPATH_DATA`). A labelled leg pair is one person at "
        "the mean of its legs, found when a detection lies within the match distance; precision counts the "
        "detections inside the labelled wedge.",
        "",
        "```bash",
        f"viapath scans $VIAPATH_DATA/{SCANS_BAG} --labels /leg_cluster_positions --json",
        "```",
        "",
    ]
    result = _json(work / SCANS)
    evaluation = (result or {}).get("evaluation")
    if not evaluation:
        return [*out, "*Not measured in this run: the recording was not found (extra `ros` and the data needed).*", ""]
    return [
        *out,
        "| scans | labelled people | person recall | person precision (in the wedge) | median position error [m] | "
        "leg recall | match distance [m] |",
        "|---|---|---|---|---|---|---|",
        f"| {evaluation.get('scans')} | {evaluation.get('labelled_people')} | {_num(evaluation.get('person_recall'), '.3f')} | "
        f"{_num(evaluation.get('person_precision_in_wedge'), '.3f')} | "
        f"{_num(evaluation.get('person_position_error_median_m'), '.3f')} | {_num(evaluation.get('leg_recall'), '.3f')} | "
        f"{_num(evaluation.get('match_distance_m'))} |",
        "",
    ]


def ros2_section(work: Path, previous: str) -> list[str]:
    out = [
        "## ROS 2: the paper's experiments over DDS",
        "",
        "The planner node and the simulator node in separate processes, in lock-step, against `viapath run "
        "SCENARIO --perception laser` of the same scenario (ROS 2 / run).",
        "",
        "```bash",
        "python benchmarks/ros2_paper_table.py",
        "```",
        "",
    ]
    table = (work / ROS2_TABLE).read_text().strip() if (work / ROS2_TABLE).exists() else _previous_table(previous)
    return [*out, table or "*Not measured in this run: run the command above (extra `ros2`).*", ""]


def _previous_table(previous: str) -> str:
    """The ROS 2 table of the current page, kept when this run did not measure it."""
    match = re.search(
        r"## ROS 2: the paper's experiments over DDS\n.*?```\n\n(\|[^\n]*(?:\n\|[^\n]*)*)", previous, flags=re.S
    )
    return match.group(1).strip() if match else ""


def speed_section(work: Path) -> list[str]:
    out = [
        "## Speed",
        "",
        "Wall-clock figures depend on the machine and its load: measure on a quiet machine, three runs each. "
        "The benchmarks print their own tables, shown here as printed.",
        "",
    ]
    for name, argv in SPEED:
        out += ["```bash", "python " + " ".join(argv), "```", ""]
        path = work / name
        if path.exists():
            out += ["```text", path.read_text().rstrip(), "```", ""]
        else:
            out += ["*Not measured in this run.*", ""]
    return out


def _machine() -> str:
    from viapath import __version__

    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    from viapath import jit

    compiled = "compiled steps (numba)" if jit.enabled() else "steps as plain Python (NUMBA_DISABLE_JIT)"
    return f"viapath {__version__}, Python {platform.python_version()}, {compiled}; {cpu}, {os.cpu_count()} cores"


def render(work: Path, workers: int, previous: str) -> str:
    lines = [
        "# Results",
        "",
        "<!-- Generated by benchmarks/results_page.py from the runs it names; do not edit by hand. -->",
        "",
        "Every figure on this page was printed by the command shown above it; the page is rewritten by",
        "`python benchmarks/results_page.py` (it runs what is missing, then writes this page) or",
        "`python benchmarks/results_page.py --from DIR` (it reads the outputs in DIR). Counts and rates depend",
        "only on the seeds; what the columns mean is explained in [the benchmark's metrics](explanation/metrics.md).",
        "",
        "Measured with "
        + ((work / MACHINE).read_text().strip() if (work / MACHINE).exists() else "(not recorded in the runs' folder)")
        + ".",
        "",
    ]
    lines += paper_section(work)
    by_name = {b.name: b for b in BENCHES}
    lines += bench_section(
        work,
        "Generated encounters (`mixed`)",
        "200 scenarios from nine families of encounters (crossing, head-on, overtaken, overtaking, several "
        "people, groups, crowds, hallways, the paper's cases), two suite seeds; viapath with its defaults.",
        [("mixed, seed 0", by_name["mixed0"]), ("mixed, seed 3", by_name["mixed3"])],
        workers,
    )
    if (work / "mixed0-peers" / "summary.json").exists():
        lines += bench_section(
            work,
            "Every planner on the same suite",
            "The same 200 scenarios (seed 0) for viapath (shield on) and the other planners (shield off, their "
            "default); navground's planners need the extra `navground`.",
            [("mixed, seed 0", by_name["mixed0-peers"])],
            workers,
        )
    lines += bench_section(
        work,
        "Real pedestrians (`eth-ucy`)",
        "100 episodes replaying the ETH/UCY pedestrian data sets (people do not react to the robot); needs the "
        "data (`$VIAPATH_DATA`, see [run a benchmark](howto/benchmark-cluster.md)).",
        [("eth-ucy, seed 7", by_name["eth7"])],
        workers,
    )
    lines += bench_section(
        work,
        "The static world (`static`)",
        "50 scenes of boxes, carts, pillars, doors and walled corridors with people; in some the door never "
        "opens and the goal cannot be reached. Oracle and laser perception.",
        [("static, seed 11, oracle", by_name["static11"]), ("static, seed 11, laser", by_name["static11laser"])],
        workers,
    )
    lines += scans_section(work)
    lines += ros2_section(work, previous)
    if any((work / name).exists() for name, _ in SPEED):
        lines += speed_section(work)
    return "\n".join(lines).rstrip() + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--work", type=Path, default=ROOT / "out" / "results", help="folder of the runs' outputs")
    parser.add_argument("--from", dest="source", type=Path, help="read the outputs in this folder; run nothing")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--with", dest="extras", default="", help="also measure: peers, ros2, speed (comma-separated)")
    parser.add_argument("--out", type=Path, default=PAGE, help="the page to write")
    parser.add_argument("--check", action="store_true", help="write nothing; exit 1 if the page would change")
    args = parser.parse_args(argv)
    extras = {e for e in args.extras.split(",") if e}
    unknown = extras - {"peers", "ros2", "speed"}
    if unknown:
        parser.error(f"--with: unknown {', '.join(sorted(unknown))}; use peers, ros2, speed")
    work = args.source or args.work
    if args.source is None:
        measure(work, args.workers, extras)
    elif not work.is_dir():
        parser.error(f"--from: {work} is not a folder")
    previous = args.out.read_text() if args.out.exists() else ""
    text = render(work, args.workers, previous)
    if args.check:
        if text != previous:
            print(f"{args.out} is stale: run python benchmarks/results_page.py --from {work}", file=sys.stderr)
            return 1
        return 0
    args.out.write_text(text)
    print(f"wrote {args.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
