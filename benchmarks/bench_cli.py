"""Stand-alone entry for the benchmark commands until ``viapath.cli`` registers them.

    python benchmarks/bench_cli.py suite mixed --count 200 --seed 0 --out out/suite-mixed
    python benchmarks/bench_cli.py bench out/suite-mixed --planners viapath,dwa,vo --workers 2 --out out/run
"""

import typer

from viapath.bench.commands import register

app = typer.Typer(add_completion=False, help="viapath benchmark commands")


@app.callback()
def main() -> None:
    """viapath benchmark commands."""


register(app)

if __name__ == "__main__":
    app()
