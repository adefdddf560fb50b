"""Obstacle maps of the ETH walking-pedestrians sequences (EWAP: ``seq_eth``, ``seq_hotel``) as static walls.

Each sequence folder of the original annotation holds ``map.png`` (the authors' obstacle map in image
coordinates: bright pixels are obstacles) and ``H.txt`` (the 3x3 homography from image to world, in
metres). The world frame is the one of ``obsmat.txt`` and of the 4-column files ``biwi_eth.txt`` /
``biwi_hotel.txt`` that the ``eth-ucy`` suite replays (data README §1-§2).

The homography takes an image point as **(row, column, 1)**, not (x = column, y = row): with that
order the ETH map's building walls frame the walkers and the hotel's tram-stop shelter and pillars
lie beside the crowd, at the places OpenTraj digitised by hand in ``map.xml``; with (column, row) the
walls cut through the crowd (``tests/io/test_ewap_map.py`` measures both).

The obstacles' outlines are traced at half intensity (contourpy's marching squares, matplotlib's own
contouring), carried into the world by the homography and simplified (Douglas-Peucker) to within
``tolerance_m``: a closed polyline per obstacle (a wall drawn a few pixels wide becomes a thin
closed outline). :meth:`ObstacleMap.walls_in_box` cuts them to a box around a path, as open polylines.
"""

from __future__ import annotations

import io
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from viapath.io.safe_read import read_bytes, read_text_file

MAX_MAP_BYTES = 16 * 1024 * 1024  # B; the EWAP maps are 1-2 kB
# The EWAP sequence folder of each replayed trajectory file of the eth-ucy suite (data README §1-§2).
EWAP_FOLDER = "eth_ewap_original"
EWAP_SEQUENCES = {"biwi_eth.txt": "seq_eth", "biwi_hotel.txt": "seq_hotel"}


@dataclass(frozen=True)
class ObstacleMap:
    """Obstacle outlines in the world frame: closed polylines (first point repeated last), m."""

    outlines: tuple[np.ndarray, ...]

    def segments(self) -> np.ndarray:
        """Every outline edge, (M, 2, 2)."""
        if not self.outlines:
            return np.zeros((0, 2, 2))
        return np.concatenate([np.stack([ring[:-1], ring[1:]], axis=1) for ring in self.outlines])

    def contains(self, points: np.ndarray) -> np.ndarray:
        """Whether each point (N, 2) lies inside an obstacle (even-odd rule over all outlines, so a hole in
        an obstacle is free)."""
        points = np.asarray(points, dtype=float).reshape(-1, 2)
        inside = np.zeros(len(points), dtype=bool)
        x, y = points[:, 0:1], points[:, 1:2]
        for ring in self.outlines:
            (x1, y1), (x2, y2) = ring[:-1].T[:, None, :], ring[1:].T[:, None, :]
            straddles = (y1 > y) != (y2 > y)
            with np.errstate(divide="ignore", invalid="ignore"):
                x_cross = x1 + (y - y1) * (x2 - x1) / (y2 - y1)
            inside ^= (np.count_nonzero(straddles & (x < x_cross), axis=1) % 2).astype(bool)
        return inside

    def walls_in_box(self, low: np.ndarray, high: np.ndarray) -> list[np.ndarray]:
        """The outlines' parts inside the axis-aligned box [low, high] (m), as open polylines (K, 2): an
        outline that leaves the box is cut where it crosses the box's edge (no edge is added along it)."""
        low, high = np.asarray(low, dtype=float), np.asarray(high, dtype=float)
        polylines: list[np.ndarray] = []
        for ring in self.outlines:
            pieces: list[list[np.ndarray]] = []
            for a, b in zip(ring[:-1], ring[1:]):
                piece = _clip_segment(a, b, low, high)
                if piece is None or np.array_equal(piece[0], piece[1]):
                    continue
                if pieces and np.array_equal(piece[0], pieces[-1][-1]):
                    pieces[-1].append(piece[1])
                else:
                    pieces.append([piece[0], piece[1]])
            if len(pieces) > 1 and np.array_equal(pieces[-1][-1], pieces[0][0]):  # the cut runs through the start
                pieces[0] = pieces.pop()[:-1] + pieces[0]
            polylines += [np.array(piece) for piece in pieces]
        return polylines


def read_homography(path: str | Path) -> np.ndarray:
    """The 3x3 image-to-world homography of an ``H.txt`` (whitespace-separated rows)."""
    text = read_text_file(path, what="homography (3 rows of 3 numbers)")
    try:
        matrix = np.loadtxt(io.StringIO(text), ndmin=2)
    except ValueError as error:
        raise ValueError(f"{path}: expected 3 rows of 3 numbers: {error}") from None
    if matrix.shape != (3, 3) or not np.isfinite(matrix).all():
        raise ValueError(f"{path}: expected a finite 3x3 matrix, found shape {matrix.shape}")
    return matrix


def read_obstacle_image(path: str | Path) -> np.ndarray:
    """The obstacle map as an image (rows, columns) in [0, 1]: the brightest channel of a PNG."""
    import matplotlib.image

    data = read_bytes(path, MAX_MAP_BYTES, what="obstacle map (PNG)")
    try:
        image = np.asarray(matplotlib.image.imread(io.BytesIO(data), format="png"), dtype=float)
    except (OSError, ValueError, SyntaxError) as error:
        raise ValueError(f"{path}: not a readable PNG image: {error}") from None
    if image.ndim == 3:
        image = image[..., :3].max(axis=2) if image.shape[2] >= 3 else image[..., 0]
    if image.ndim != 2 or min(image.shape) < 2:
        raise ValueError(f"{path}: expected a 2-D image, found shape {image.shape}")
    return image


def image_to_world(homography: np.ndarray, rows: np.ndarray, columns: np.ndarray) -> np.ndarray:
    """World points (N, 2), m, of image points given as rows and columns (pixels; EWAP order (row, column))."""
    rows, columns = np.asarray(rows, dtype=float), np.asarray(columns, dtype=float)
    projected = np.asarray(homography, dtype=float) @ np.vstack([rows, columns, np.ones_like(rows)])
    return (projected[:2] / projected[2]).T


def obstacle_map(image: np.ndarray, homography: np.ndarray, tolerance_m: float = 0.05) -> ObstacleMap:
    """The outlines of the bright (>= 0.5) regions of ``image`` in the world frame of ``homography``,
    simplified to within ``tolerance_m``; outlines enclosing less than 1 cm² are left out."""
    import contourpy

    padded = np.pad(np.asarray(image, dtype=float), 1)  # so that obstacles touching the border close
    lines = contourpy.contour_generator(z=padded, line_type=contourpy.LineType.Separate).lines(0.5)
    outlines = []
    for line in lines:
        pixels = np.asarray(line, dtype=float)
        world = image_to_world(homography, pixels[:, 1] - 1.0, pixels[:, 0] - 1.0)
        if np.any(world[0] != world[-1]):
            world = np.vstack([world, world[:1]])
        if abs(_area(world)) < 1e-4:
            continue
        outlines.append(_simplify_ring(world, tolerance_m))
    return ObstacleMap(tuple(outlines))


def read_obstacle_map(folder: str | Path, tolerance_m: float = 0.05) -> ObstacleMap:
    """:func:`obstacle_map` of an EWAP sequence folder's ``map.png`` and ``H.txt``."""
    folder = Path(folder)
    return obstacle_map(read_obstacle_image(folder / "map.png"), read_homography(folder / "H.txt"), tolerance_m)


def sequence_folder(data_root: str | Path, trajectory_file: str | Path) -> Path | None:
    """The EWAP sequence folder whose map belongs to a replayed trajectory file (by its name), or None
    when there is none (the UCY scenes have no obstacle map)."""
    sequence = EWAP_SEQUENCES.get(Path(trajectory_file).name)
    return None if sequence is None else Path(data_root) / EWAP_FOLDER / sequence


def _area(ring: np.ndarray) -> float:
    x, y = ring[:, 0], ring[:, 1]
    return 0.5 * float(np.sum(x[:-1] * y[1:] - x[1:] * y[:-1]))


def _simplify_ring(ring: np.ndarray, tolerance_m: float) -> np.ndarray:
    """A closed polyline simplified to within ``tolerance_m`` (Douglas-Peucker on the two halves between
    its first point and the point farthest from it)."""
    far = int(np.argmax(np.hypot(*(ring - ring[0]).T)))
    if far == 0:
        return ring[[0, 0]]
    first, second = _simplify(ring[: far + 1], tolerance_m), _simplify(ring[far:], tolerance_m)
    return np.vstack([first, second[1:]])


def _simplify(points: np.ndarray, tolerance_m: float) -> np.ndarray:
    """Douglas-Peucker: the fewest of ``points`` (ends kept) whose polyline stays within ``tolerance_m``."""
    keep = np.zeros(len(points), dtype=bool)
    keep[[0, -1]] = True
    stack = [(0, len(points) - 1)]
    while stack:
        start, end = stack.pop()
        if end - start < 2:
            continue
        a, b = points[start], points[end]
        inner = points[start + 1 : end]
        direction = b - a
        length = float(np.hypot(*direction))
        if length == 0.0:
            distances = np.hypot(*(inner - a).T)
        else:
            distances = np.abs(direction[0] * (inner[:, 1] - a[1]) - direction[1] * (inner[:, 0] - a[0])) / length
        k = int(np.argmax(distances))
        if distances[k] > tolerance_m:
            keep[start + 1 + k] = True
            stack += [(start, start + 1 + k), (start + 1 + k, end)]
    return points[keep]


def _clip_segment(a: np.ndarray, b: np.ndarray, low: np.ndarray, high: np.ndarray) -> np.ndarray | None:
    """The part of segment a-b inside the box (Liang-Barsky), (2, 2), or None."""
    t0, t1 = 0.0, 1.0
    delta = b - a
    for axis in (0, 1):
        for p, q in ((-delta[axis], a[axis] - low[axis]), (delta[axis], high[axis] - a[axis])):
            if p == 0.0:
                if q < 0.0:
                    return None
                continue
            t = q / p
            if p < 0.0:
                t0 = max(t0, t)
            else:
                t1 = min(t1, t)
    if t0 > t1:
        return None
    return np.array([a + t0 * delta if t0 > 0.0 else a, a + t1 * delta if t1 < 1.0 else b])
