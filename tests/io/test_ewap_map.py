"""EWAP obstacle maps (map.png + H.txt) as world-frame walls: the reader's pieces on made-up input, and on the
real ETH and hotel maps that the map lands beside the recorded walkers and where OpenTraj's map.xml says."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from viapath.bench.suites import data_root
from viapath.io.ewap_map import (
    ObstacleMap,
    image_to_world,
    obstacle_map,
    read_homography,
    read_obstacle_image,
    read_obstacle_map,
    sequence_folder,
)
from viapath.static import point_segment_distances

EWAP = data_root() / "eth_ewap_original"
TRAJECTRON = data_root() / "eth_ucy_trajectron"
needs_data = pytest.mark.skipif(
    not (EWAP.is_dir() and TRAJECTRON.is_dir()),
    reason=f"ETH data not found at {EWAP} and {TRAJECTRON} (set VIAPATH_DATA)",
)
SCENES = [("seq_eth", "biwi_eth.txt"), ("seq_hotel", "biwi_hotel.txt")]


def _square(x0, y0, x1, y1) -> np.ndarray:
    return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1], [x0, y0]], dtype=float)


def test_image_points_go_through_the_homography_as_row_then_column():
    homography = np.array([[2.0, 0.0, 1.0], [0.0, 3.0, 0.0], [0.0, 0.0, 1.0]])
    world = image_to_world(homography, rows=np.array([1.0, 0.0]), columns=np.array([0.0, 1.0]))
    np.testing.assert_allclose(world, [[3.0, 0.0], [1.0, 3.0]])
    projective = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 2.0]])
    np.testing.assert_allclose(image_to_world(projective, np.array([4.0]), np.array([6.0])), [[2.0, 3.0]])


def test_a_bright_block_becomes_one_closed_outline_around_it():
    image = np.zeros((20, 30))
    image[5:10, 10:25] = 1.0  # rows 5-9, columns 10-24
    (outline,) = obstacle_map(image, np.eye(3), tolerance_m=0.01).outlines
    np.testing.assert_array_equal(outline[0], outline[-1])
    low, high = outline.min(axis=0), outline.max(axis=0)
    np.testing.assert_allclose(low, [4.5, 9.5])  # (row, column) = world (x, y), the edge at half intensity
    np.testing.assert_allclose(high, [9.5, 24.5])
    assert len(outline) <= 9  # a rectangle simplified: its corners (the marching squares cut them at 45°)
    map_ = ObstacleMap((outline,))
    assert map_.contains(np.array([[7.0, 15.0], [3.0, 15.0], [7.0, 26.0]])).tolist() == [True, False, False]


def test_an_obstacle_on_the_image_border_still_closes():
    image = np.zeros((10, 10))
    image[:, :3] = 1.0
    (outline,) = obstacle_map(image, np.eye(3)).outlines
    assert ObstacleMap((outline,)).contains(np.array([[5.0, 1.0]]))[0]


def test_walls_in_box_cut_an_outline_at_the_box_edge_without_adding_one():
    ring = _square(0.0, 0.0, 10.0, 1.0)
    walls = ObstacleMap((ring,)).walls_in_box(np.array([2.0, -5.0]), np.array([5.0, 5.0]))
    # the long sides' middle pieces, no edge along x = 2 or x = 5
    assert sorted(tuple(map(tuple, w.round(9))) for w in walls) == [((2.0, 0.0), (5.0, 0.0)), ((5.0, 1.0), (2.0, 1.0))]
    # an outline whose start lies inside the box and that leaves it: the piece through the start is one polyline
    walls = ObstacleMap((_square(0.0, 0.0, 10.0, 1.0),)).walls_in_box(np.array([-1.0, -1.0]), np.array([3.0, 3.0]))
    assert len(walls) == 1
    np.testing.assert_allclose(walls[0], [[3.0, 1.0], [0.0, 1.0], [0.0, 0.0], [3.0, 0.0]])
    # wholly inside: the closed outline as it is; wholly outside: nothing
    inside = ObstacleMap((ring,)).walls_in_box(np.array([-1.0, -1.0]), np.array([11.0, 2.0]))
    assert len(inside) == 1 and np.array_equal(inside[0], ring)
    assert ObstacleMap((ring,)).walls_in_box(np.array([20.0, 20.0]), np.array([30.0, 30.0])) == []


def test_unreadable_inputs_are_errors_naming_the_file(tmp_path):
    bad_h = tmp_path / "H.txt"
    bad_h.write_text("1 0\n0 1\n")
    with pytest.raises(ValueError, match=r"H\.txt"):
        read_homography(bad_h)
    bad_png = tmp_path / "map.png"
    bad_png.write_bytes(b"not a png")
    with pytest.raises(ValueError, match=r"map\.png"):
        read_obstacle_image(bad_png)


def test_only_eth_and_hotel_have_a_map_folder():
    assert sequence_folder("/d", "x/biwi_eth.txt") == Path("/d/eth_ewap_original/seq_eth")
    assert sequence_folder("/d", "biwi_hotel.txt") == Path("/d/eth_ewap_original/seq_hotel")
    assert sequence_folder("/d", "crowds_zara01.txt") is None


def _walkers(file: str) -> np.ndarray:
    return np.loadtxt(TRAJECTRON / file, ndmin=2)[:, 2:4]


def _beside_not_under(map_: ObstacleMap, walkers: np.ndarray) -> tuple[float, int]:
    """(fraction of walker positions inside an obstacle, fewest positions within 1 m outside any one outline)."""
    if not map_.outlines:
        return 0.0, 0
    inside = map_.contains(walkers)
    around = [
        int(
            np.count_nonzero(
                (point_segment_distances(walkers, ObstacleMap((ring,)).segments()).min(axis=1) < 1.0) & ~inside
            )
        )
        for ring in map_.outlines
    ]
    return float(inside.mean()), min(around)


@needs_data
@pytest.mark.parametrize(("sequence", "file"), SCENES)
def test_the_map_lands_beside_the_walkers_not_under_them(sequence, file):
    """Measured: ETH 0 of 5492 positions inside the walls, at least 72 within 1 m of each wall outline;
    hotel 9 of 6543 inside (0.14 %, in the tram-stop shelter), at least 102 round each obstacle. With the
    image's (column, row) fed to H instead (and with H transposed) the check fails: the ETH walls cut
    through the crowd (1.2 % inside) or lie where nobody walks, the hotel shelter and a pillar lie off the
    walked area (0-2 positions round them), and H transposed maps nothing to a finite outline."""
    folder = EWAP / sequence
    image, homography = read_obstacle_image(folder / "map.png"), read_homography(folder / "H.txt")
    walkers = _walkers(file)

    def holds(map_: ObstacleMap) -> bool:
        inside, fewest_around = _beside_not_under(map_, walkers)
        return inside <= 0.005 and fewest_around >= 50

    map_ = obstacle_map(image, homography)
    assert len(map_.outlines) >= 2
    inside, fewest_around = _beside_not_under(map_, walkers)
    assert inside <= 0.005, inside
    assert fewest_around >= 50, fewest_around
    assert not holds(obstacle_map(image.T, homography))  # (column, row) into H
    assert not holds(obstacle_map(image, homography.T))


def _map_xml_lines(sequence: str) -> np.ndarray:
    text = (EWAP / sequence / "map.xml").read_text()
    numbers = [
        [float(v) for v in match]
        for match in re.findall(r'<Line x1="([^"]+)" y1="([^"]+)" x2="([^"]+)" y2="([^"]+)"', text)
    ]
    return np.array(numbers).reshape(-1, 2, 2)


def _distances_to_obstacles(map_: ObstacleMap, points: np.ndarray) -> np.ndarray:
    """0 inside an obstacle, else the distance to the nearest outline."""
    distance = point_segment_distances(points, map_.segments()).min(axis=1)
    return np.where(map_.contains(points), 0.0, distance)


@needs_data
@pytest.mark.parametrize("sequence", ["seq_eth", "seq_hotel"])
def test_opentraj_map_xml_lines_lie_on_the_map_png_obstacles(sequence):
    """OpenTraj digitised map.xml by hand; every 10 cm along each of its lines is within 0.3 m of the
    map.png obstacles (measured: all of them inside, max 2 mm off). With (column, row) into H they are
    0.5-6 m off."""
    lines = _map_xml_lines(sequence)
    assert len(lines) >= 4
    steps = np.linspace(0.0, 1.0, 50)[:, None]
    samples = np.concatenate([a * (1 - steps) + b * steps for a, b in lines])
    folder = EWAP / sequence
    image, homography = read_obstacle_image(folder / "map.png"), read_homography(folder / "H.txt")
    assert _distances_to_obstacles(obstacle_map(image, homography), samples).max() <= 0.3
    assert np.median(_distances_to_obstacles(obstacle_map(image.T, homography), samples)) > 1.0


@needs_data
def test_map_xml_pillars_of_the_hotel_are_inside_map_png_pillars():
    text = (EWAP / "seq_hotel" / "map.xml").read_text()
    centres = np.array([[float(x), float(y)] for x, y in re.findall(r'<Circle x="([^"]+)" y="([^"]+)"', text)])
    assert len(centres) == 3
    assert read_obstacle_map(EWAP / "seq_hotel").contains(centres).all()
