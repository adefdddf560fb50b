"""The ``eth-ucy-maps`` suite: the ``eth-ucy`` scenarios, the ETH and hotel ones with their obstacle map as
walls near the path; ``eth-ucy`` itself unchanged."""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
import pytest
import yaml

from viapath.bench.suites import (
    ETH_UCY_MAP_END_CLEARANCE_M,
    ETH_UCY_MAP_MARGIN_M,
    data_root,
    generate_suite,
    write_suite,
)
from viapath.scenarios import load_scenario
from viapath.static import point_segment_distances

DATA = data_root()
needs_data = pytest.mark.skipif(
    not ((DATA / "eth_ucy_trajectron").is_dir() and (DATA / "eth_ewap_original").is_dir()),
    reason=f"ETH/UCY data not found at {DATA} (set VIAPATH_DATA)",
)


def _digest(scenarios: list[dict]) -> str:
    for scenario in scenarios:
        for item in scenario["obstacles"]:
            item["replay"]["file"] = Path(item["replay"]["file"]).name  # the data folder's place is not the suite
    return hashlib.sha256(yaml.safe_dump(scenarios, sort_keys=True).encode()).hexdigest()


@needs_data
def test_without_maps_the_eth_ucy_suites_are_as_before():
    # Digests of seed 0, count 20 from the code before the maps existed (commit dd4bc23).
    assert (
        _digest(generate_suite("eth-ucy", 20, 0)) == "303a2d8e550bdb5602da1ac2984ecfb3ad033f85194e812bb70a3a95e5ab2abb"
    )
    assert (
        _digest(generate_suite("eth-ucy-react", 20, 0))
        == "a79e3f8110405f32c899cf8d54557cf0be88175db96888b783f05d833d819fe2"
    )


def _ends_to_map_m(scenario: dict) -> float:
    """How far the path's ends lie from the scene's map obstacles (0 inside one)."""
    from viapath.io.ewap_map import read_obstacle_map, sequence_folder

    obstacles = read_obstacle_map(sequence_folder(DATA, scenario["obstacles"][0]["replay"]["file"]))
    ends = np.asarray(scenario["path"]["waypoints"])[[0, -1]]
    distance = point_segment_distances(ends, obstacles.segments()).min(axis=1)
    return float(np.where(obstacles.contains(ends), 0.0, distance).min())


@needs_data
def test_with_maps_the_scenarios_are_the_same_plus_walls_inside_the_clip_box(tmp_path):
    plain, mapped = generate_suite("eth-ucy", 20, 0), generate_suite("eth-ucy-maps", 20, 0)
    with_walls = 0
    for before, after in zip(plain, mapped):
        assert after["name"] == before["name"].replace("eth-ucy-", "eth-ucy-maps-")
        walls = after.pop("walls", [])
        assert {k: v for k, v in after.items() if k not in ("name", "description")} == {
            k: v for k, v in before.items() if k not in ("name", "description")
        }
        scene = before["name"].split("-")[2]
        if scene not in ("eth", "hotel"):
            assert walls == []
            continue
        with_walls += bool(walls)
        waypoints = np.asarray(after["path"]["waypoints"])
        reach = after["path"]["half_width"] + ETH_UCY_MAP_MARGIN_M + 1e-4  # + the YAML's rounding
        for wall in walls:
            points = np.asarray(wall["points"])
            assert len(points) >= 2
            assert (points >= waypoints.min(axis=0) - reach).all() and (points <= waypoints.max(axis=0) + reach).all()
    assert with_walls >= 4  # the four hotel windows of 20 have the shelter or pillars near the path

    files = write_suite(mapped, tmp_path)
    for file, data in zip(files, mapped):
        scenario = load_scenario(file)  # validates (extra="forbid")
        assert scenario.name == data["name"]
        assert len(scenario.walls) == len(data.get("walls", []))
        if scenario.walls:
            assert scenario.static_shapes()[0][0].shape[1:] == (2, 2)


@needs_data
def test_with_maps_a_path_whose_end_meets_the_map_is_drawn_again():
    """Seed 0: of 182 windows, hotel 131 and 181 start 0.24 and 0.21 m from a pillar or the shelter (the robot
    would start touching it); with maps they are placed again, clear of it; every other window is kept."""
    plain, mapped = generate_suite("eth-ucy", 182, 0), generate_suite("eth-ucy-maps", 182, 0)
    moved = [after["name"] for before, after in zip(plain, mapped) if before["path"] != after["path"]]
    assert moved == ["eth-ucy-maps-hotel-0131", "eth-ucy-maps-hotel-0181"]
    for before, after in zip(plain, mapped):
        if before["name"].split("-")[2] not in ("eth", "hotel"):
            continue
        assert _ends_to_map_m(after) >= ETH_UCY_MAP_END_CLEARANCE_M
        if after["name"] in moved:
            assert _ends_to_map_m(before) < ETH_UCY_MAP_END_CLEARANCE_M
