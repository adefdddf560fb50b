"""``viapath ros2 node | sim | play | params``: the ROS 2 commands as a typer sub-app.

Registered into the main app by ``register(app)``; rclpy is imported only when a command runs, so
``viapath --help`` works without the ``ros2`` extra. Arguments after ``--ros-args`` go to rclpy
unchanged (``-p name:=value``, ``--params-file``, remappings ``-r from:=to``).
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import List, Optional

import typer
from rich.console import Console
from rich.markup import escape

app = typer.Typer(add_completion=False, no_args_is_help=True,
                  help="viapath on a robot: the ROS 2 planner node, a simulator node, a bag player.")
_errors = Console(stderr=True)

_CONTEXT = {"allow_extra_args": True, "ignore_unknown_options": True}


def _fail(message: str, code: int = 2) -> None:
    _errors.print(f"[bold red]error:[/] {escape(message)}", highlight=False, soft_wrap=True)
    raise typer.Exit(code)


def _need_rclpy() -> None:
    from viapath.ros2 import rclpy_available

    ok, why = rclpy_available()
    if not ok:
        _fail(why)


def _ros_args(extra: list[str]) -> list[str]:
    """Arguments after ``--ros-args`` (typer leaves them in ``ctx.args``)."""
    if not extra:
        return []
    if extra[0] == "--ros-args":
        return extra[1:]
    _fail(f"unexpected argument {extra[0]!r}; ROS arguments go after --ros-args")
    return []


@app.command(context_settings=_CONTEXT)
def node(
    ctx: typer.Context,
    params_file: Optional[Path] = typer.Option(None, "--params-file", help="ROS 2 parameters file (viapath: ros__parameters: ...)."),
    use_sim_time: bool = typer.Option(False, "--use-sim-time", help="Run on /clock (as with the simulator node)."),
) -> None:
    """The planner node: scans + odometry + designated path in, cmd_vel out (see docs/ros2.md)."""
    from viapath.ros2.settings import ParameterError, read_params_file, validate

    ros_args = _ros_args(ctx.args)
    if params_file is not None:
        try:
            values = read_params_file(params_file)
            values.pop("use_sim_time", None)
            validate(values)
        except ParameterError as error:
            _fail(f"{params_file}: {error}")
        ros_args = ["--params-file", str(params_file), *ros_args]
    if use_sim_time:
        ros_args = [*ros_args, "-p", "use_sim_time:=true"]
    _need_rclpy()
    from viapath.ros2.node import run_node

    raise typer.Exit(run_node(ros_args))


@app.command(context_settings=_CONTEXT)
def sim(
    ctx: typer.Context,
    scenario: str = typer.Argument(..., help="Built-in scenario name (viapath scenarios) or a YAML file."),
    rate: float = typer.Option(1.0, "--rate", help="Run R times faster than real time (through /clock)."),
    lockstep: bool = typer.Option(False, "--lockstep", help="Wait for the node's command of each step before driving."),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object of metrics (as viapath run --json)."),
    seed: Optional[int] = typer.Option(None, "--seed", help="Random seed of the range noise (default: the scenario's)."),
    fault: List[str] = typer.Option([], "--fault", help="Inject a fault from T (to END) s: silence:NAME@T[-END], nan:NAME@T[-END], short:NAME@T[-END], odom@T[-END], clock-back:D@T."),
    trace: Optional[Path] = typer.Option(None, "--trace", help="Write the per-step trace as CSV."),
    commands: Optional[Path] = typer.Option(None, "--commands", help="Write every step's received command as CSV."),
    status_log: Optional[Path] = typer.Option(None, "--status-log", help="Write every planner status received (JSON lines)."),
    wait_s: float = typer.Option(60.0, "--wait-s", help="How long to wait for a planner node to appear."),
    duration: Optional[float] = typer.Option(None, "--duration", help="End the episode after this many seconds (default: the scenario's)."),
) -> None:
    """Simulated scans, odometry and /clock from a scenario; drives the robot with cmd_vel; prints the metrics."""
    import math

    from viapath.ros2.sim_node import Fault, run_sim
    from viapath.scenarios import ScenarioError, load_scenario

    ros_args = _ros_args(ctx.args)
    if not (math.isfinite(rate) and rate > 0):
        _fail(f"--rate: expected a number > 0, found {rate}")
    if seed is not None and seed < 0:
        _fail(f"--seed: expected an integer >= 0, found {seed}")
    if duration is not None and not (math.isfinite(duration) and duration > 0):
        _fail(f"--duration: expected a number > 0, found {duration}")
    try:
        load_scenario(scenario)
        faults = [Fault.parse(f) for f in fault]
    except (ScenarioError, ValueError) as error:
        _fail(str(error))
    for file, option, suffix in ((trace, "--trace", ".csv"), (commands, "--commands", ".csv"), (status_log, "--status-log", ".jsonl")):
        if file is not None and (file.suffix.lower() != suffix or not file.parent.exists()):
            _fail(f"{option} {file}: expected a {suffix} file in an existing folder")
    _need_rclpy()
    try:
        code = run_sim(scenario, rate=rate, lockstep=lockstep, as_json=as_json, seed=seed, faults=faults,
                       trace_file=str(trace) if trace else None, wait_for_node_s=wait_s,
                       commands_file=str(commands) if commands else None, ros_args=ros_args,
                       duration_s=duration, status_file=str(status_log) if status_log else None)
    except ValueError as error:
        _fail(str(error))
    raise typer.Exit(code)


@app.command(context_settings=_CONTEXT)
def play(
    ctx: typer.Context,
    bag: Path = typer.Argument(..., help="ROS 1 .bag, ROS 2 bag folder or .mcap with sensor_msgs/LaserScan."),
    topic: Optional[str] = typer.Option(None, "--topic", help="LaserScan topic in the bag (default: the only one)."),
    out_topic: str = typer.Option("scan_front", "--out-topic", help="Topic to publish the scans on."),
    frame_id: Optional[str] = typer.Option(None, "--frame-id", help="frame_id to stamp (default: the bag's)."),
    rate: float = typer.Option(1.0, "--rate", help="Play R times faster, through /clock."),
    odom: bool = typer.Option(True, "--odom/--no-odom", help="Also publish a standing robot's odometry at the origin."),
    wait_s: float = typer.Option(30.0, "--wait-s", help="How long to wait for a subscriber before playing."),
    lockstep: bool = typer.Option(False, "--lockstep", help="Wait for the node's cycle on each scan before the next."),
    status_log: Optional[Path] = typer.Option(None, "--status-log", help="Write the node's planner statuses (JSON lines)."),
) -> None:
    """Publish a recording's scans with their timing (and /clock), so the node tracks real people.

    Exits 4 when the node ran no cycle on them (it refused every scan, or no node reported)."""
    import math

    from viapath.ros2.play import run_play

    ros_args = _ros_args(ctx.args)
    if not (math.isfinite(rate) and rate > 0):
        _fail(f"--rate: expected a number > 0, found {rate}")
    if not bag.exists():
        _fail(f"{bag}: no such file or directory")
    _need_rclpy()
    try:
        code = run_play(bag, topic, out_topic, frame_id, rate, odom, wait_s, ros_args, lockstep=lockstep,
                        status_file=str(status_log) if status_log else None)
    except (ValueError, ImportError, FileNotFoundError) as error:
        _fail(str(error))
    raise typer.Exit(code)


@app.command()
def params(
    out: Path = typer.Argument(..., help="Write a parameters file with every parameter at its default."),
    planner: str = typer.Option("viapath", "--planner", help="Planner whose options to include."),
) -> None:
    """Write an example parameters file (units and bounds as comments)."""
    from viapath.planning import available_planners
    from viapath.ros2.settings import write_example_params

    if planner not in available_planners():
        _fail(f"--planner: unknown planner {planner!r}; available: {', '.join(available_planners())}")
    if not out.parent.exists():
        _fail(f"{out}: folder {out.parent} does not exist")
    write_example_params(out, planner)
    print(out)


def register(root: typer.Typer) -> None:
    root.add_typer(app, name="ros2")


if __name__ == "__main__":  # pragma: no cover
    app(sys.argv[1:])
