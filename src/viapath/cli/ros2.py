"""``viapath ros2 node | sim | play | params``: the ROS 2 commands as a typer sub-app.

Mounted as ``viapath ros2``; rclpy is imported only when a command runs, so
``viapath --help`` works without the ``ros2`` extra. Arguments after ``--ros-args`` go to rclpy
unchanged (``-p name:=value``, ``--params-file``, remappings ``-r from:=to``).
"""

from __future__ import annotations

import sys
from pathlib import Path

import typer

from viapath.cli.common import errors, fail

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    help="viapath on a robot: the ROS 2 planner node, a simulator node, a bag player.",
)
_CONTEXT = {"allow_extra_args": True, "ignore_unknown_options": True}


def _need_rclpy() -> None:
    from viapath.ros2 import rclpy_available

    ok, why = rclpy_available()
    if not ok:
        fail(why)


def _ros_args(extra: list[str]) -> list[str]:
    """Arguments after ``--ros-args`` (typer leaves them in ``ctx.args``)."""
    if not extra:
        return []
    if extra[0] == "--ros-args":
        return extra[1:]
    fail(f"unexpected argument {extra[0]!r}; ROS arguments go after --ros-args")
    return []


@app.command(context_settings=_CONTEXT)
def node(
    ctx: typer.Context,
    params_file: Path | None = typer.Option(
        None, "--params-file", help="ROS 2 parameters file (viapath: ros__parameters: ...)."
    ),
    use_sim_time: bool = typer.Option(False, "--use-sim-time", help="Run on /clock (as with the simulator node)."),
) -> None:
    """The planner node: scans + odometry + designated path in, cmd_vel out (see docs/ros2.md)."""
    _run_node(_ros_args(ctx.args), params_file, use_sim_time)


def _run_node(ros_args: list[str], params_file: Path | None, use_sim_time: bool, nav2_name: str | None = None) -> None:
    """Check the parameters file (as the node named ``nav2_name`` with ``interface: nav2`` when given), then run
    the node with it and ``ros_args``."""
    from viapath.ros2.settings import NODE_NAME, ParameterError, read_params_file, validate

    if params_file is not None:
        try:
            values = read_params_file(params_file, node_name=nav2_name or NODE_NAME)
            values.pop("use_sim_time", None)
            if nav2_name is not None:
                values.setdefault("interface", "nav2")
            validate(values)
        except ParameterError as error:
            fail(f"{params_file}: {error}")
        ros_args = ["--params-file", str(params_file), *ros_args]
    if nav2_name is not None:
        ros_args = ["-r", f"__node:={nav2_name}", "-p", "interface:=nav2", "-p", "autostart:=false", *ros_args]
    if use_sim_time:
        ros_args = [*ros_args, "-p", "use_sim_time:=true"]
    _need_rclpy()
    from viapath.ros2.node import run_node

    raise typer.Exit(run_node(ros_args))


@app.command(context_settings=_CONTEXT)
def nav2(
    ctx: typer.Context,
    params_file: Path | None = typer.Option(
        None, "--params-file", help="ROS 2 parameters file (controller_server: ros__parameters: ...)."
    ),
    use_sim_time: bool = typer.Option(False, "--use-sim-time", help="Run on /clock."),
    name: str = typer.Option(
        "controller_server", "--name", help="Node name (Nav2's lifecycle manager manages nodes by name)."
    ),
) -> None:
    """The planner as Nav2's controller server: serves follow_path, honours speed_limit, reads TF (see docs/nav2.md)."""
    _run_node(_ros_args(ctx.args), params_file, use_sim_time, nav2_name=name)


@app.command(context_settings=_CONTEXT)
def sim(
    ctx: typer.Context,
    scenario: str = typer.Argument(..., help="Built-in scenario name (viapath scenarios) or a YAML file."),
    rate: float = typer.Option(1.0, "--rate", help="Run R times faster than real time (through /clock)."),
    lockstep: bool = typer.Option(False, "--lockstep", help="Wait for the node's command of each step before driving."),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object of metrics (as viapath run --json)."),
    seed: int | None = typer.Option(None, "--seed", help="Random seed of the range noise (default: the scenario's)."),
    fault: list[str] = typer.Option(
        [],
        "--fault",
        help="Inject a fault from T (to END) s: silence:NAME@T[-END], nan:NAME@T[-END], short:NAME@T[-END], odom@T[-END], clock-back:D@T.",
    ),
    trace: Path | None = typer.Option(None, "--trace", help="Write the per-step trace as CSV."),
    commands: Path | None = typer.Option(None, "--commands", help="Write every step's received command as CSV."),
    status_log: Path | None = typer.Option(
        None, "--status-log", help="Write every planner status received (JSON lines)."
    ),
    wait_s: float = typer.Option(60.0, "--wait-s", help="How long to wait for a planner node to appear."),
    duration: float | None = typer.Option(
        None, "--duration", help="End the episode after this many seconds (default: the scenario's)."
    ),
    tf: bool = typer.Option(
        True, "--tf/--no-tf", help="Publish TF: /tf odom->base_link, /tf_static map->odom and base_link->laser_NAME."
    ),
    map_offset: str = typer.Option(
        "0,0,0", "--map-offset", help="map->odom as X,Y,YAW (m, m, rad): the pose of odom in map."
    ),
    max_wait: float = typer.Option(
        10.0, "--max-wait", help="With --lockstep: wait at most this long (wall s) for the node each step."
    ),
    linger: float = typer.Option(
        2.0,
        "--linger",
        help="After the goal, keep simulating this long (s; not in the metrics), so the node sees the robot there.",
    ),
) -> None:
    """Simulated scans, odometry and /clock from a scenario; drives the robot with cmd_vel; prints the metrics."""
    from viapath.ros2.sim_node import Fault, run_sim
    from viapath.scenarios import ScenarioError, load_scenario

    ros_args = _ros_args(ctx.args)
    offset = _check_sim_arguments(rate, seed, duration, map_offset)
    try:
        load_scenario(scenario)
        faults = [Fault.parse(f) for f in fault]
    except (ScenarioError, ValueError) as error:
        fail(str(error))
    for file, option, suffix in (
        (trace, "--trace", ".csv"),
        (commands, "--commands", ".csv"),
        (status_log, "--status-log", ".jsonl"),
    ):
        if file is not None and (file.suffix.lower() != suffix or not file.parent.exists()):
            fail(f"{option} {file}: expected a {suffix} file in an existing folder")
    _need_rclpy()
    try:
        code = run_sim(
            scenario,
            rate=rate,
            lockstep=lockstep,
            max_wait_s=max(max_wait, 0.0),
            as_json=as_json,
            seed=seed,
            faults=faults,
            trace_file=str(trace) if trace else None,
            wait_for_node_s=wait_s,
            commands_file=str(commands) if commands else None,
            ros_args=ros_args,
            duration_s=duration,
            status_file=str(status_log) if status_log else None,
            tf=tf,
            map_offset=offset,
            linger_s=max(linger, 0.0),
        )
    except ValueError as error:
        fail(str(error))
    raise typer.Exit(code)


def _check_sim_arguments(rate: float, seed: int | None, duration: float | None, map_offset: str) -> tuple:
    """Refuse a bad --rate, --seed or --duration; the --map-offset pose (x, y, yaw)."""
    import math

    if not (math.isfinite(rate) and rate > 0):
        fail(f"--rate: expected a number > 0, found {rate}")
    if seed is not None and seed < 0:
        fail(f"--seed: expected an integer >= 0, found {seed}")
    if duration is not None and not (math.isfinite(duration) and duration > 0):
        fail(f"--duration: expected a number > 0, found {duration}")
    try:
        offset = tuple(float(v) for v in map_offset.split(","))
    except ValueError:
        offset = ()
    if len(offset) != 3 or not all(math.isfinite(v) for v in offset):
        fail(f"--map-offset: expected X,Y,YAW (three finite numbers), found {map_offset!r}")
    return offset


@app.command(context_settings=_CONTEXT)
def play(
    ctx: typer.Context,
    bag: Path = typer.Argument(..., help="ROS 1 .bag, ROS 2 bag folder or .mcap with sensor_msgs/LaserScan."),
    topic: str | None = typer.Option(None, "--topic", help="LaserScan topic in the bag (default: the only one)."),
    out_topic: str = typer.Option("scan_front", "--out-topic", help="Topic to publish the scans on."),
    frame_id: str | None = typer.Option(None, "--frame-id", help="frame_id to stamp (default: the bag's)."),
    rate: float = typer.Option(1.0, "--rate", help="Play R times faster, through /clock."),
    odom: bool = typer.Option(True, "--odom/--no-odom", help="Also publish a standing robot's odometry at the origin."),
    wait_s: float = typer.Option(30.0, "--wait-s", help="How long to wait for a subscriber before playing."),
    lockstep: bool = typer.Option(False, "--lockstep", help="Wait for the node's cycle on each scan before the next."),
    status_log: Path | None = typer.Option(
        None, "--status-log", help="Write the node's planner statuses (JSON lines)."
    ),
) -> None:
    """Publish a recording's scans with their timing (and /clock), so the node tracks real people.

    Exits 4 when the node ran no cycle on them (it refused every scan, or no node reported)."""
    import math

    from viapath.ros2.play import run_play

    ros_args = _ros_args(ctx.args)
    if not (math.isfinite(rate) and rate > 0):
        fail(f"--rate: expected a number > 0, found {rate}")
    if not bag.exists():
        fail(f"{bag}: no such file or directory")
    _need_rclpy()
    try:
        code = run_play(
            bag,
            topic,
            out_topic,
            frame_id,
            rate,
            odom,
            wait_s,
            ros_args,
            lockstep=lockstep,
            status_file=str(status_log) if status_log else None,
        )
    except (ValueError, ImportError, FileNotFoundError) as error:
        fail(str(error))
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
        fail(f"--planner: unknown planner {planner!r}; available: {', '.join(available_planners())}")
    if not out.parent.exists():
        fail(f"{out}: folder {out.parent} does not exist")
    write_example_params(out, planner)
    print(out)


@app.command(context_settings=_CONTEXT)
def follow(
    ctx: typer.Context,
    source: str = typer.Argument(
        ..., help="Path: a built-in scenario, a scenario YAML, or a path file (YAML/CSV of x y)."
    ),
    action: str = typer.Option("follow_path", "--action", help="FollowPath action name."),
    frame: str = typer.Option("map", "--frame", help="Frame the path is sent in."),
    map_offset: str = typer.Option(
        "0,0,0", "--map-offset", help="Pose of the path's odometry frame in --frame: X,Y,YAW."
    ),
    spacing: float = typer.Option(
        0.05, "--spacing", help="Densify the path to poses this far apart (m), as a planner's path."
    ),
    resend: float = typer.Option(
        1.0, "--resend", help="Re-send the path every S seconds (0: once), as Nav2's behaviour tree."
    ),
    lifecycle: str | None = typer.Option(None, "--lifecycle", help="Configure and activate this lifecycle node first."),
    at: list[str] = typer.Option(
        [],
        "--at",
        help="Event TIME:KIND[:ARG]: empty, nan, preempt:PATH, cancel, deactivate, activate, speed-limit:PERCENT, clear, stop.",
    ),
    log: Path | None = typer.Option(None, "--log", help="Append every goal, result and feedback as JSON lines here."),
    until: float = typer.Option(
        float("inf"), "--until", help="End at this episode time (s) if the path goal has no result by then."
    ),
    use_sim_time: bool = typer.Option(
        True, "--use-sim-time/--wall-time", help="Episode time from /clock (the simulator's)."
    ),
    wait_s: float = typer.Option(
        120.0,
        "--wait-s",
        help="How long (wall s) to wait for the node's lifecycle service and action server, and for a stopped clock.",
    ),
) -> None:
    """Play Nav2's part against a controller (viapath ros2 nav2): lifecycle, FollowPath goals re-sent every second.

    Ends with the path goal's result, printed: exit 0 when it succeeded (or was canceled by --at T:cancel),
    1 when it failed, 5 when no result came (--until, or the clock stopped for --wait-s)."""
    import math

    from viapath.ros2.nav2_client import parse_event, run_follow

    ros_args = _ros_args(ctx.args)
    try:
        offset = tuple(float(v) for v in map_offset.split(","))
        for item in at:
            parse_event(item)
    except ValueError as error:
        fail(str(error))
    if len(offset) != 3 or not all(math.isfinite(v) for v in offset):
        fail(f"--map-offset: expected X,Y,YAW, found {map_offset!r}")
    if use_sim_time:
        ros_args = [*ros_args, "-p", "use_sim_time:=true"] if ros_args else ["-p", "use_sim_time:=true"]
    _need_rclpy()
    raise typer.Exit(
        run_follow(
            source,
            action,
            frame,
            offset,
            spacing,
            resend,
            lifecycle,
            list(at),
            str(log) if log else None,
            until,
            ros_args,
            wait_s=wait_s,
        )
    )


@app.command()
def interfaces() -> None:
    """Generate and build nav2_msgs / tf2_msgs (FollowPath, SpeedLimit, ClearEntireCostmap, TFMessage) once; print where."""
    import time

    from viapath.ros2 import interfaces as generated

    started, built_before = time.monotonic(), generated.is_built()
    try:
        if errors.is_terminal and not built_before:
            prefix = _build_with_bar(generated)
        else:
            prefix = generated.build(progress=lambda text: errors.print(text, highlight=False))
    except generated.InterfaceBuildError as error:
        fail(str(error))
    if not built_before:
        errors.print(f"built in {time.monotonic() - started:.0f} s", highlight=False)
    print(prefix)


def _build_with_bar(generated):
    """The build with a bar on the terminal: the step in words, the share done from make's percentages."""
    from rich.progress import BarColumn, Progress, TaskProgressColumn, TextColumn, TimeElapsedColumn

    with Progress(
        TextColumn("interfaces"), BarColumn(), TaskProgressColumn(), TimeElapsedColumn(),
        TextColumn("{task.description}"), console=errors,
    ) as bar:  # fmt: skip
        job = bar.add_task("", total=1.0)
        return generated.build(
            progress=lambda text: bar.update(job, description=text.split(" into ")[0]),
            fraction=lambda done: bar.update(job, completed=done),
        )


if __name__ == "__main__":  # pragma: no cover
    app(sys.argv[1:])
