"""The laser loop's fast paths change nothing (issue 16).

* ``simulate_scans`` (every scanner in one pass, angular culling of discs) gives the readings of
  ``simulate_scan`` per scanner, bit for bit, and draws the same numbers from the generator.
* The numba back end (ray casting and circle fit) gives the numpy back end's ranges (to 1e-9, in
  fact bit for bit), the same segments, and after a run of cycles the same tracks.
Random scenes: hypothesis, derandomized, bounded.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from viapath.compiled import numba_available
from viapath.perception.base import WorldSnapshot
from viapath.perception.detection import detect
from viapath.perception.laser import LaserPerception, ray_casters
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
    backends = ["numpy"] + (["numba"] if numba_available() else [])
    for backend in backends:
        one_rng = np.random.default_rng(seed)
        one_origin, per_beam = ray_casters(backend)
        single = [simulate_scan(s, pose, centres, radii, walls, one_rng, one_origin) for s in scanners]
        all_rng = np.random.default_rng(seed)
        fused = simulate_scans(scanners, pose, centres, radii, walls, all_rng, per_beam)
        for a, b in zip(single, fused, strict=True):
            np.testing.assert_array_equal(a, b)  # NaN == NaN here; bit for bit otherwise
        assert one_rng.random() == all_rng.random()  # the same draws were taken


def test_culling_keeps_a_disc_seen_across_the_scan_seam():
    """A disc right behind a 360° scanner (where beam 0 meets beam B-1) is hit by beams at both ends."""
    scanner = ScannerModel(name="ring", beam_count=1024, angle_increment_rad=2 * np.pi / 1024, mount_x_m=0.0)
    readings = simulate_scans((scanner,), np.zeros(3), [[-2.0, 0.0]], [0.3])[0]
    hit = np.flatnonzero(np.isfinite(readings))
    assert 0 in hit and scanner.beam_count - 1 in hit
    assert np.isclose(readings[0], 1.7, atol=1e-3) and np.isclose(readings[-1], 1.7, atol=1e-3)


needs_numba = pytest.mark.skipif(not numba_available(), reason="numba not installed (extra 'fast')")


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


@needs_numba
@settings(max_examples=12, deadline=None, derandomize=True)
@given(st.integers(1, 10), st.integers(0, 2**31))
def test_numba_laser_path_equals_numpy_segments_and_tracks(n_people, seed):
    rng = np.random.default_rng(seed)
    distance = rng.uniform(1.0, 3.5, n_people)
    bearing = rng.uniform(-np.pi, np.pi, n_people)
    centres0 = np.stack([distance * np.cos(bearing), distance * np.sin(bearing)], -1)
    velocities = rng.uniform(-0.5, 0.5, (n_people, 2))
    walls = np.array([[[-10.0, -4.0], [20.0, -4.0]], [[-10.0, 4.0], [20.0, 4.0]]])
    runs = {}
    for backend in ("numpy", "numba"):
        perception = LaserPerception(ray_compute=backend, detector={"keep_segments": True, "fit_compute": backend})
        perception.reset(np.random.default_rng(seed))
        ranges, segments, reported = [], [], []
        for k in range(25):
            world = _world(k, centres0, velocities, walls)
            scans = perception.scan(world)
            ranges.append(np.concatenate(scans))
            segments.append(detect(perception.scanners, scans, perception.detector_params).segments)
            reported.append(perception.process(world.time_s, world.robot_pose, scans))
        runs[backend] = ranges, segments, reported, perception.tracks
    (r_np, s_np, o_np, t_np), (r_nb, s_nb, o_nb, t_nb) = runs["numpy"], runs["numba"]
    for a, b in zip(r_np, r_nb, strict=True):
        finite = np.isfinite(a)
        assert np.array_equal(finite, np.isfinite(b))
        assert np.max(np.abs(a[finite] - b[finite]), initial=0.0) <= 1e-9
    for a, b in zip(s_np, s_nb, strict=True):
        assert len(a) == len(b)
        for x, y in zip(a, b, strict=True):
            assert x["scanner"] == y["scanner"] and x["accepted"] == y["accepted"]
            np.testing.assert_array_equal(x["points"], y["points"])
            np.testing.assert_allclose(x["centre"], y["centre"], atol=1e-9)
    for a, b in zip(o_np, o_nb, strict=True):
        assert list(a.ids) == list(b.ids)
        np.testing.assert_allclose(a.positions, b.positions, atol=1e-9)
        np.testing.assert_allclose(a.velocities, b.velocities, atol=1e-9)
    assert [t.track_id for t in t_np] == [t.track_id for t in t_nb]
    assert [t.confirmed for t in t_np] == [t.confirmed for t in t_nb]
    assert sum(len(a) for a in o_np) > 0  # something was tracked: the comparison is not empty
