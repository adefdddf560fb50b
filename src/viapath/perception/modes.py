"""Perception modes by name: what ``perception.mode`` in a scenario, ``--perception`` on the command
line and the benchmark accept. Each mode is a factory ``(options, position_noise_m,
velocity_noise_mps) -> Perception``; the lists in the CLI help and the scenario schema come from here.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable
from typing import Any

from viapath.perception.base import Perception
from viapath.perception.laser import LaserPerception
from viapath.perception.oracle import OraclePerception
from viapath.registry import Registry

PerceptionFactory = Callable[[dict[str, Any], float, float], Perception]
PERCEPTION_MODES: Registry[PerceptionFactory] = Registry("perception mode")


@PERCEPTION_MODES.register("oracle")
def _oracle(options: dict[str, Any], position_noise_m: float, velocity_noise_mps: float) -> Perception:
    return OraclePerception(position_noise_m, velocity_noise_mps)


@PERCEPTION_MODES.register("laser")
def _laser(options: dict[str, Any], position_noise_m: float, velocity_noise_mps: float) -> Perception:
    return options_as_arguments(LaserPerception, options)


def make_perception(
    mode: str, options: dict[str, Any] | None = None, position_noise_m: float = 0.0, velocity_noise_mps: float = 0.0
) -> Perception:
    return PERCEPTION_MODES.get(mode)(dict(options or {}), position_noise_m, velocity_noise_mps)


def options_as_arguments(cls, options: dict[str, Any]) -> Perception:
    """The scenario's ``perception.options`` as keyword arguments, with errors naming that field."""
    known = list(inspect.signature(cls).parameters)
    unknown = sorted(set(options) - set(known))
    if unknown:
        raise ValueError(f"perception.options: unknown option(s) {', '.join(unknown)}; known: {', '.join(known)}")
    try:
        return cls(**options)
    except (TypeError, ValueError) as error:
        raise ValueError(f"perception.options: {error}") from None
