"""The interface build tells how far it is: make's ``[ p%]`` lines become a share of the build, and
``viapath ros2 interfaces`` draws them as a bar on a terminal (the build takes about two minutes)."""

from __future__ import annotations

import io

from rich.console import Console

from viapath.ros2 import interfaces


def test_make_percentages_reach_the_callback_and_the_log(tmp_path):
    log = tmp_path / "build.log"
    seen: list[int] = []
    script = (
        "echo '-- configuring'; echo '[  5%] Generating C code'; echo '[ 57%] Building C object'; echo '[100%] Built'"
    )
    interfaces._run(["sh", "-c", script], tmp_path, {"PATH": "/usr/bin:/bin"}, log, percent=seen.append)
    assert seen == [5, 57, 100]
    assert "[ 57%] Building C object" in log.read_text() and "-- configuring" in log.read_text()


def test_a_failing_step_names_the_log_and_its_tail(tmp_path):
    log = tmp_path / "build.log"
    try:
        interfaces._run(["sh", "-c", "echo 'cc: error: boom'; exit 3"], tmp_path, {"PATH": "/usr/bin:/bin"}, log)
    except interfaces.InterfaceBuildError as error:
        assert "exit 3" in str(error) and str(log) in str(error) and "boom" in str(error)
    else:
        raise AssertionError("a failing step must raise")


def test_the_command_draws_a_bar_from_the_builds_shares(monkeypatch):
    import viapath.cli.ros2 as ros2_cli

    class FakeBuild:
        InterfaceBuildError = interfaces.InterfaceBuildError

        @staticmethod
        def build(progress=None, fraction=None):
            for package, share in (("tf2_msgs", 0.0), ("tf2_msgs", 0.3), ("nav2_msgs", 0.5), ("nav2_msgs", 1.0)):
                progress(f"building {package} into /cache/x")
                fraction(share)
            return "/cache/x"

    screen = io.StringIO()
    monkeypatch.setattr(ros2_cli, "errors", Console(file=screen, force_terminal=True, width=100))
    assert ros2_cli._build_with_bar(FakeBuild) == "/cache/x"
    shown = screen.getvalue()
    assert "100%" in shown and "building nav2_msgs" in shown and "/cache/x" not in shown
