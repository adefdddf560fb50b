"""The laser loop's one pass and its one implementation.

* ``simulate_scans`` (every scanner in one pass) gives the readings of ``simulate_scan`` per scanner, bit for
  bit, and draws the same numbers from the generator. Random scenes: hypothesis, derandomized, bounded.
* The laser chain compiled (numba) and run as plain Python (``NUMBA_DISABLE_JIT=1``, what a debugger steps
  through): the same scans, segments, tracks and static layer, bit for bit, over a run of cycles.
"""

from __future__ import annotations

import hashlib
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from viapath.jit import enabled
from viapath.perception.base import WorldSnapshot
from viapath.perception.detection import detect
from viapath.perception.laser import LaserPerception
from viapath.perception.raycast import simulate_scan, simulate_scans
from viapath.perception.scanner import ScannerModel, paper_scanners

coordinate = st.floats(-6.0, 6.0, allow_nan=False)


@st.composite
def scenes(draw):
    n = draw(st.integers(0, 12))
    pose = np.array([draw(coordinate), draw(coordinate), draw(st.floats(-7.0, 7.0))])
    centres = np.array([[draw(coordinate), draw(coordinate)] for _ in range(n)]).reshape(-1, 2)
    radii = np.array([draw(st.floats(0.0, 0.8)) for _ in range(n)])
    if n and draw(st.booleans()):  # a disc over (or next to) the robot: a scanner may sit inside it
        centres[0] = pose[:2] + np.array([draw(st.floats(-0.4, 0.4)), draw(st.floats(-0.4, 0.4))])
    walls = np.array(
        [
            [[draw(coordinate), draw(coordinate)], [draw(coordinate), draw(coordinate)]]
            for _ in range(draw(st.integers(0, 3)))
        ]
    ).reshape(-1, 2, 2)
    return pose, centres, radii, walls, draw(st.integers(0, 2**31))


SCANNER_SETS = [
    paper_scanners(),
    paper_scanners(invalid_encoding="zero"),
    (
        ScannerModel(
            name="wide",
            beam_count=1024,
            angle_increment_rad=2 * np.pi / 1024,
            invalid_encoding="nan",
            mount_x_m=0.05,
            mount_yaw_rad=0.3,
        ),
    ),
]


@settings(max_examples=150, deadline=None, derandomize=True)
@given(scenes(), st.sampled_from(range(len(SCANNER_SETS))))
def test_all_scanners_in_one_pass_equal_one_scanner_at_a_time(scene, which):
    pose, centres, radii, walls, seed = scene
    scanners = SCANNER_SETS[which]
    one_rng = np.random.default_rng(seed)
    single = [simulate_scan(s, pose, centres, radii, walls, one_rng) for s in scanners]
    all_rng = np.random.default_rng(seed)
    fused = simulate_scans(scanners, pose, centres, radii, walls, all_rng)
    for a, b in zip(single, fused, strict=True):
        np.testing.assert_array_equal(a, b)  # NaN == NaN here; bit for bit otherwise
    assert one_rng.random() == all_rng.random()  # the same draws were taken


def test_a_disc_seen_across_the_scan_seam_is_hit_at_both_ends():
    """A disc right behind a 360° scanner (where beam 0 meets beam B-1) is hit by beams at both ends."""
    scanner = ScannerModel(name="ring", beam_count=1024, angle_increment_rad=2 * np.pi / 1024, mount_x_m=0.0)
    readings = simulate_scans((scanner,), np.zeros(3), [[-2.0, 0.0]], [0.3])[0]
    hit = np.flatnonzero(np.isfinite(readings))
    assert 0 in hit and scanner.beam_count - 1 in hit
    assert np.isclose(readings[0], 1.7, atol=1e-3) and np.isclose(readings[-1], 1.7, atol=1e-3)


def _world(k, centres0, velocities, walls):
    t = 0.1 * k
    return WorldSnapshot(
        t,
        np.array([0.2 * t, 0.0, 0.05 * t]),
        0.25,
        centres0 + velocities * t,
        velocities,
        np.full(len(centres0), 0.25),
        walls,
    )


def laser_run_digest(n_people: int, seed: int, cycles: int) -> tuple[str, int]:
    """The SHA-256 (16 hex digits) of every scan, detected segment, reported track and static layer of
    ``cycles`` cycles of the laser chain on people walking between two walls, and the number of reported tracks."""
    rng = np.random.default_rng(seed)
    distance = rng.uniform(1.0, 3.5, n_people)
    bearing = rng.uniform(-np.pi, np.pi, n_people)
    centres0 = np.stack([distance * np.cos(bearing), distance * np.sin(bearing)], -1)
    velocities = rng.uniform(-0.5, 0.5, (n_people, 2))
    walls = np.array([[[-10.0, -4.0], [20.0, -4.0]], [[-10.0, 4.0], [20.0, 4.0]]])
    perception = LaserPerception(detector={"keep_segments": True})
    perception.reset(np.random.default_rng(seed))
    digest, reported = hashlib.sha256(), 0
    for k in range(cycles):
        world = _world(k, centres0, velocities, walls)
        scans = perception.scan(world)
        for segment in detect(perception.scanners, scans, perception.detector_params).segments:
            digest.update(np.concatenate([segment["points"].ravel(), segment["centre"]]).tobytes())
            digest.update(bytes([segment["accepted"]]))
        obstacles = perception.process(world.time_s, world.robot_pose, scans)
        reported += len(obstacles)
        layer = perception.last_static
        for part in (*scans, obstacles.positions, obstacles.velocities, layer.segments, layer.radii_m):
            digest.update(np.ascontiguousarray(part, dtype=float).tobytes())
    return digest.hexdigest()[:16], reported


def test_the_plain_python_run_is_the_compiled_run_bit_for_bit():
    """NUMBA_DISABLE_JIT=1 runs the very functions that are compiled otherwise: the same bits come out."""
    if not enabled():
        pytest.skip("compilation is off here: nothing to compare the plain run with")
    compiled = laser_run_digest(6, 3, 8)
    assert compiled[1] > 0  # people were tracked: the comparison is not empty
    env = {**os.environ, "NUMBA_DISABLE_JIT": "1"}
    env["PYTHONPATH"] = os.pathsep.join([str(Path(__file__).resolve().parents[2] / "src"), env.get("PYTHONPATH", "")])
    script = "from tests.perception.test_laser_one_pass import laser_run_digest; print(laser_run_digest(6, 3, 8))"
    root = Path(__file__).resolve().parents[2]
    done = subprocess.run(
        [sys.executable, "-c", script], env=env, cwd=root, capture_output=True, text=True, timeout=600
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip().splitlines()[-1] == repr(compiled)
