"""Perception modes by name: what ``perception.mode`` in a scenario, ``--perception`` on the command
line and the benchmark accept. Each mode is a factory ``(options, position_noise_m,
velocity_noise_mps) -> Perception``; the lists in the CLI help and the scenario schema come from here.
The laser chain's options are :class:`~viapath.perception.laser_options.LaserOptions` (a scenario's
``perception.options``).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

from pydantic import BaseModel, ValidationError

from viapath.perception.base import Perception
from viapath.perception.laser import LaserPerception
from viapath.perception.laser_options import LaserOptions
from viapath.perception.oracle import OraclePerception, TrackedOraclePerception
from viapath.registry import Registry

PerceptionFactory = Callable[[Any, float, float], Perception]
PERCEPTION_MODES: Registry[PerceptionFactory] = Registry("perception mode")


@PERCEPTION_MODES.register("oracle")
def _oracle(options: Any, position_noise_m: float, velocity_noise_mps: float) -> Perception:
    return OraclePerception(position_noise_m, velocity_noise_mps)


@PERCEPTION_MODES.register("tracked")
def _tracked(options: Any, position_noise_m: float, velocity_noise_mps: float) -> Perception:
    return TrackedOraclePerception(position_noise_m, velocity_noise_mps)


@PERCEPTION_MODES.register("laser")
def _laser(options: Any, position_noise_m: float, velocity_noise_mps: float) -> Perception:
    return laser_perception(options)


def make_perception(
    mode: str,
    options: Any = None,
    position_noise_m: float = 0.0,
    velocity_noise_mps: float = 0.0,
) -> Perception:
    """``options``: a :class:`LaserOptions` (a scenario's ``perception.options``), a mapping of them or None."""
    return PERCEPTION_MODES.get(mode)(options, position_noise_m, velocity_noise_mps)


def laser_options(options: BaseModel | Mapping[str, Any] | None) -> Any:
    """``options`` as :class:`LaserOptions`: a mapping is validated, with errors naming the field path under
    ``perception.options``."""
    if isinstance(options, LaserOptions):
        return options
    try:
        return LaserOptions.model_validate(dict(options or {}))
    except ValidationError as error:
        lines = []
        for item in error.errors(include_url=False):
            path = ".".join(str(part) for part in ("perception.options", *item["loc"]))
            lines.append(f"{path}: {item['msg']}")
        raise ValueError("\n".join(lines)) from None


def laser_perception(options: BaseModel | Mapping[str, Any] | None) -> Perception:
    """A :class:`LaserPerception` with the options the scenario set (its defaults for the rest)."""
    given = laser_options(options).given()
    try:
        return LaserPerception(**given)
    except (TypeError, ValueError) as error:
        raise ValueError(f"perception.options: {error}") from None
