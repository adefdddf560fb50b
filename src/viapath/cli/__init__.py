"""The ``viapath`` command line (docs/design.md §4): one typer app, every command imported here by name.

Each command lives in a module of this package and imports what is heavy (the simulator, rclpy,
Optuna, Foxglove, navground, matplotlib) inside its body, so ``viapath --help`` and ``viapath run``
need none of the extras.

* :mod:`viapath.cli.run`: ``run``, ``precompile``
* :mod:`viapath.cli.catalogue`: ``scenarios``, ``planners``
* :mod:`viapath.cli.scans`: ``scans``
* :mod:`viapath.cli.bench`: ``suite``, ``bench``
* :mod:`viapath.cli.ros2`: ``ros2 node | nav2 | sim | play | params | follow | interfaces``
* :mod:`viapath.cli.tune`: ``presets``, ``tune``
* :mod:`viapath.cli.extras`: ``--version`` and the help's plain flags
"""

from __future__ import annotations

import typer

from viapath.cli import bench, catalogue, extras, ros2, run, scans, tune
from viapath.cli.run import parse_options

__all__ = ["app", "main", "parse_options"]

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    help="Follow a designated path and avoid moving obstacles by choosing speed as well as direction.",
)
app.command("run")(run.run)
app.command("precompile")(run.precompile)
app.command("scenarios")(catalogue.scenarios)
app.command("planners")(catalogue.planners)
app.command("scans")(scans.scans)
app.command("suite")(bench.suite)
app.command("bench")(bench.bench)
app.add_typer(ros2.app, name="ros2")
app.command("presets")(tune.presets)
app.command("tune")(tune.tune)
extras.install(app)


def main() -> None:  # pragma: no cover
    app()
