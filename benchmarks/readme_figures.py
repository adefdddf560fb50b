"""Regenerate the README's pictures and the numbers written beside them, from the runs they describe.

Usage: python benchmarks/readme_figures.py [--check]

Runs the paper's three experiments (``viapath run paper-behind|paper-front|paper-side``, oracle
perception, shield on as by default) and paper-front without the shield, then

* draws ``docs/img/paper-front.png`` (``viapath run paper-front --plot``) and
  ``docs/img/xyt-paper-front.png`` (``python -m viapath.viz.xyt_plot paper-front ... --time 0.5``);
* rewrites the README text between ``<!-- generated:NAME -->`` and ``<!-- /generated:NAME -->``
  from the metrics of those runs, so no number there is typed by hand.

``--check`` changes nothing and exits 1 when the README's generated text differs from what the runs
give now (tests/test_readme.py does the same).
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
IMAGES = ROOT / "docs" / "img"


def runs() -> dict[str, dict]:
    """Metrics of the runs the README describes, by a short key."""
    from viapath.scenarios import load_scenario
    from viapath.sim.loop import run_episode

    out = {name: run_episode(load_scenario(name)).metrics for name in ("paper-behind", "paper-front", "paper-side")}
    out["paper-front-no-shield"] = run_episode(load_scenario("paper-front"), shield=False).metrics
    return out


def _m(value: float, digits: int = 2) -> str:
    return f"{value:.{digits}f}"


def texts(metrics: dict[str, dict]) -> dict[str, str]:
    """The README's generated blocks, from the metrics."""
    behind, front, side = metrics["paper-behind"], metrics["paper-front"], metrics["paper-side"]
    bare = metrics["paper-front-no-shield"]
    every_goal = all(
        m["reached_goal"] and not m["collision"] and not m["shield_interventions"] for m in (behind, front, side)
    )
    caption = (
        "*`viapath run paper-front --plot front.png`: a person walks towards the robot at 0.3 m/s (circles,\n"
        "every 1 s). The robot (drawn every 0.5 s, size ∝ speed; stars while it heads for a via point ×)\n"
        f"speeds up to {_m(front['max_speed_mps'], 1)} m/s towards a via point on the left (wide enough that it "
        "could brake in time, the shield's envelope), passes\n"
        f"{_m(front['min_clearance_m'])} m from the person at the closest, and returns to its nominal 0.2 m/s — "
        "never leaving the corridor (blue).*"
    )
    paper = (
        "* **The paper's three experiments** (`viapath run paper-behind|paper-front|paper-side --json`,\n"
        "  oracle perception, shield on as by default): from behind the robot speeds up to "
        f"{_m(behind['max_speed_mps'])} m/s and\n"
        f"  {'never leaves the path line' if behind['max_lateral_deviation_m'] < 0.005 else 'stays near the path line'}; "
        f"from the front it speeds up to {_m(front['max_speed_mps'], 1)} m/s and passes **on the left** "
        f"({_m(front['max_lateral_deviation_m'])} m),\n"
        f"  inside the ±1 m corridor (without the shield: {_m(bare['max_speed_mps'], 1)} m/s, "
        f"{_m(bare['max_lateral_deviation_m'])} m — the shield's braking envelope\n"
        f"  widens and slows the pass); from the side it slows to {_m(side['min_speed_mps'])} m/s, lets the person "
        "cross, and resumes\n"
        f"  0.2 m/s. {'All reach the goal without contact and without a shield intervention' if every_goal else 'See the table'} "
        "(min clearance\n"
        f"  {_m(behind['min_clearance_m'])} / {_m(front['min_clearance_m'])} / {_m(side['min_clearance_m'])} m; "
        "`benchmarks/readme_figures.py`). Tested in `tests/planning/test_paper_behaviours.py`, for every shipped\n"
        "  weights preset too."
    )
    return {"paper-front-caption": caption, "paper-experiments": paper}


def _pattern(name: str) -> re.Pattern:
    return re.compile(rf"(<!-- generated:{re.escape(name)} -->\n)(.*?)(\n<!-- /generated:{re.escape(name)} -->)", re.S)


def render(readme: str, blocks: dict[str, str]) -> str:
    for name, text in blocks.items():
        pattern = _pattern(name)
        if not pattern.search(readme):
            raise SystemExit(f"README.md: no <!-- generated:{name} --> block")
        readme = pattern.sub(lambda m, text=text: m.group(1) + text + m.group(3), readme)
    return readme


def draw_pictures() -> None:
    from viapath.scenarios import load_scenario
    from viapath.sim.loop import run_episode
    from viapath.viz import xyt_plot
    from viapath.viz.plot import plot_episode

    plot_episode(run_episode(load_scenario("paper-front"), record_perceived=True), IMAGES / "paper-front.png")
    xyt_plot.main(["paper-front", str(IMAGES / "xyt-paper-front.png"), "--time", "0.5"])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="only compare; exit 1 when the README is stale")
    args = parser.parse_args()
    readme = README.read_text()
    fresh = render(readme, texts(runs()))
    if args.check:
        if fresh != readme:
            print("README.md's generated text is stale: run python benchmarks/readme_figures.py", file=sys.stderr)
            raise SystemExit(1)
        print("README.md's generated text matches the runs")
        return
    draw_pictures()
    README.write_text(fresh)
    print(f"wrote {IMAGES / 'paper-front.png'}, {IMAGES / 'xyt-paper-front.png'} and README.md's generated text")


if __name__ == "__main__":
    main()
