"""Static shapes in the candidate tree (viapath/planning/viapath/shapes.py) against their definitions: a robot hugging
a static shape slides along it (checked on a cycle that is blocked without the slides, and against the slides'
definition); a shape's extreme discs as seen from a node against a brute force over its discs' outlines; the root's
one branch per shape against its numpy specification."""

from __future__ import annotations

import math

import numpy as np
import pytest

from viapath import DesignatedPath, Observation, Obstacles, RobotState
from viapath.planning import make_planner
from viapath.planning.viapath import planner as viapath_planner
from viapath.planning.viapath import shapes
from viapath.static import StaticLayer, polygon_edges

# Two pillars (octagons, 0.2 m across the flats) near the path, as a generated static scene has them;
# the robot stands 0.22 m from the second one, west of it, turned away from the goal.
PILLARS = [
    [(3.0654, -0.0515), (3.006, 0.0918), (2.8628, 0.1511), (2.7195, 0.0918), (2.6601, -0.0515), (2.7195, -0.1948),
     (2.8628, -0.2542), (3.006, -0.1948)],
    [(4.2948, 0.5931), (4.2268, 0.7572), (4.0628, 0.8251), (3.8987, 0.7572), (3.8307, 0.5931), (3.8987, 0.429),
     (4.0628, 0.3611), (4.2268, 0.429)],
]  # fmt: skip


def _hugging_cycle(monkeypatch, hug_factor: float | None):
    if hug_factor is not None:
        monkeypatch.setattr(shapes, "HUG_FACTOR", hug_factor)
        # the tree's own verdict: without this, the flood's way round (blocked.detour) would find the way
        monkeypatch.setattr(viapath_planner, "detour", lambda *arguments: None)
    path = DesignatedPath([[0.0, 0.0], [6.8755, 0.0]], half_width_m=1.35)
    planner = make_planner("viapath", path, nominal_speed_mps=0.28)
    static = StaticLayer.of_shapes([polygon_edges(p) for p in PILLARS])
    robot = RobotState(np.array([3.3754, 0.5588]), -0.923, 0.0, 0.0, 0.25)
    return planner.plan(Observation(0.0, robot, Obstacles.empty(), static))


def test_a_robot_hugging_a_pillar_finds_a_way_round_it(monkeypatch):
    decision = _hugging_cycle(monkeypatch, None)
    assert decision.plan.status in ("avoid", "straight"), decision.plan.status
    assert decision.command.speed_mps > 0.0
    terms = decision.plan.extras["cost_terms"]["chosen"]  # a static cycle's plan keeps Eq. 1's breakdown too
    assert set(terms) == {"distance", "time", "speed", "heading", "side", "hysteresis", "total"}
    assert terms["total"] == pytest.approx(sum(v for k, v in terms.items() if k != "total"))
    without = _hugging_cycle(monkeypatch, 0.0)
    assert without.plan.status == "blocked"  # the cycle this is about: tangents alone find no way round


def test_slides_are_one_via_radius_at_right_angles_to_the_disc():
    rng = np.random.default_rng(3)
    centres = rng.uniform(-2, 2, (6, 2))
    radii = rng.uniform(0.3, 0.6, 6)
    # nodes at 0.8-1.4 via radii from their disc, in random directions
    bearing = rng.uniform(-np.pi, np.pi, 6)
    factor = np.array([0.8, 1.0, 1.2, 1.24, 1.3, 1.4])
    starts = centres - (factor * radii)[:, None] * np.stack([np.cos(bearing), np.sin(bearing)], 1)
    hugging = [shapes.hugs(*starts[k], *centres[k], radii[k], shapes.HUG_FACTOR) for k in range(6)]
    assert hugging == [f < shapes.HUG_FACTOR for f in factor]
    assert not shapes.hugs(*centres[0], *centres[0], radii[0], shapes.HUG_FACTOR)  # on the centre: no way to slide
    for k in range(6):
        for side in (1.0, -1.0):
            t, vx, vy, ex, ey = shapes.slide(*starts[k], *centres[k], radii[k], 0.3, side)
            step, toward = np.array([ex, ey]) - starts[k], centres[k] - starts[k]
            assert np.hypot(*step) == pytest.approx(radii[k])
            assert abs(step @ toward) < 1e-9  # at right angles to the way to the disc
            assert np.sign(toward[0] * step[1] - toward[1] * step[0]) == side  # +1: left of that way
            assert np.allclose(np.array([vx, vy]) * t, step) and t == pytest.approx(radii[k] / 0.3)


def _random_shapes(rng, count: int):
    """Discs of a few shapes (walls and boxes sampled as the static layer samples them, radius each), mixed with
    people (shape -1), in random order: (positions, via radii, ids, is_static)."""
    positions, ids, static = [], [], []
    for shape in range(count):
        start, angle = rng.uniform(-3, 3, 2), rng.uniform(-np.pi, np.pi)
        along = np.linspace(0.0, rng.uniform(0.3, 3.0), int(rng.integers(1, 12)))
        bend = rng.uniform(-0.4, 0.4) * along**2  # walls bent a little: the extremes are not the ends
        direction, normal = np.array([np.cos(angle), np.sin(angle)]), np.array([-np.sin(angle), np.cos(angle)])
        positions.extend(start + along[:, None] * direction + bend[:, None] * normal)
        ids.extend([1000 + shape] * len(along))
        static.extend([True] * len(along))
    people = int(rng.integers(0, 4))
    positions.extend(rng.uniform(-3, 3, (people, 2)))
    ids.extend(range(people))
    static.extend([False] * people)
    order = rng.permutation(len(ids))
    radii = rng.uniform(0.3, 0.5, len(ids))
    return np.array(positions)[order], radii, np.array(ids)[order], np.array(static)[order]


def test_a_shapes_extremes_are_the_discs_its_outline_reaches_furthest_to_each_side_with():
    """The extremes of a shape as seen from a node: among 720 points round every via disc of the shape, the
    furthest left and right as seen from the node (bearings relative to the disc met, all within half a turn of
    it) lie on the left and right extreme's via circle; from inside a via disc of the shape, the disc met
    twice; a person's disc stays itself."""
    rng = np.random.default_rng(5)
    circle = np.linspace(-np.pi, np.pi, 720, endpoint=False)
    compared = inside = 0
    for _ in range(300):
        positions, radii, ids, static = _random_shapes(rng, int(rng.integers(1, 4)))
        found = shapes.static_shapes(static, ids)
        node = rng.uniform(-4, 4, 2)
        met = int(rng.choice(np.flatnonzero(static)))
        left, right = shapes.extremes(*node, met, positions, radii, found)
        members = np.flatnonzero(ids == ids[met])
        offset = positions[members] - node
        if np.any(np.hypot(*offset.T) <= radii[members]):
            assert (left, right) == (met, met)
            inside += 1
            continue
        outline = positions[members][:, None] + radii[members][:, None, None] * np.stack(
            [np.cos(circle), np.sin(circle)], -1
        )  # (discs, 720, 2)
        reference = math.atan2(*(positions[met] - node)[::-1])
        bearing = np.arctan2(outline[..., 1] - node[1], outline[..., 0] - node[0]) - reference
        bearing = (bearing + np.pi) % (2 * np.pi) - np.pi
        if np.abs(bearing).max() > np.pi * 0.95:
            continue  # the shape wraps round the node: left and right mean nothing there
        tolerance = 2 * np.pi / 720
        assert bearing[np.flatnonzero(members == left)[0]].max() >= bearing.max() - tolerance
        assert bearing[np.flatnonzero(members == right)[0]].min() <= bearing.min() + tolerance
        assert left in members and right in members
        compared += 1
    person = int(np.flatnonzero(~static)[0]) if (~static).any() else None
    if person is not None:
        assert shapes.round_static_shapes(
            np.zeros((1, 10)), (np.zeros(1, np.int64), np.array([person]), 1), positions, radii, found
        )[1][:1].tolist() == [person]
    assert compared > 150 and inside > 5


def _one_per_shape_specification(free, contact, static, ids):
    """The root's contacts with only the earliest discs of each static shape kept per blocked leg (numpy)."""
    blocked = ~free & np.isfinite(contact).any(axis=1)
    kept = contact.copy()
    hit = static & np.isfinite(contact[blocked]).any(axis=0)
    for label in np.unique(ids[hit]):
        columns = np.flatnonzero(hit & (ids == label))
        earliest = np.minimum.reduce(contact[:, columns], axis=1)
        kept[:, columns] = np.where(contact[:, columns] == earliest[:, None], contact[:, columns], np.inf)
    return np.where(blocked[:, None], kept, contact)


def test_the_root_branches_once_per_shape_on_its_earliest_disc():
    rng = np.random.default_rng(7)
    changed = 0
    for _ in range(300):
        _, _, ids, static = _random_shapes(rng, int(rng.integers(1, 4)))
        legs = int(rng.integers(1, 6))
        contact = np.where(rng.uniform(size=(legs, len(ids))) < 0.5, rng.uniform(0, 5, (legs, len(ids))), np.inf)
        contact[rng.uniform(size=contact.shape) < 0.05] = 2.5  # ties
        free = rng.uniform(size=legs) < 0.2
        got = shapes.one_per_shape(free, contact, shapes.static_shapes(static, ids))
        expected = _one_per_shape_specification(free, contact, static, ids)
        blocked = ~free & np.isfinite(contact).any(axis=1)
        assert np.array_equal(got[blocked], expected[blocked])
        changed += int((got[blocked] != contact[blocked]).sum())
        for k in np.flatnonzero(blocked):  # each shape the leg meets keeps its earliest contact
            for label in np.unique(ids[static & np.isfinite(contact[k])]):
                columns = static & (ids == label)
                assert np.isfinite(got[k, columns]).any() and got[k, columns].min() == contact[k, columns].min()
    assert changed > 200
