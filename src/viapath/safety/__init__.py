"""Passive safety (docs/design.md §7): a shield between any planner and the base, and a planner wrapper."""

from viapath.safety.options import SHIELD_MODES, SHIELD_OPTIONS
from viapath.safety.shield import Shield, ShieldConfig, ShieldResult
from viapath.safety.shielded import SHIELDED_BY_DEFAULT, ShieldedPlanner, shield_default, shielded

__all__ = [
    "SHIELDED_BY_DEFAULT",
    "SHIELD_MODES",
    "SHIELD_OPTIONS",
    "Shield",
    "ShieldConfig",
    "ShieldResult",
    "ShieldedPlanner",
    "shield_default",
    "shielded",
]
