"""Compile viapath's compiled code now (or load it from its on-disk cache), for a long run that should take it
from its first cycle: ``viapath bench`` before its workers start, the ROS 2 node before it makes its planner and
shield. Without the extra ``fast`` it does nothing and the numpy code runs (docs/speed.md).

It lives beside the compiled package (:mod:`viapath.compiled`), not in it: it builds a planner and a shield,
which import that package.
"""

from __future__ import annotations


def precompile() -> bool:
    """The shield's compiled test, then the planner's whole-step code (about 40 s of CPU once per machine);
    True when both are ready."""
    from viapath.planning.viapath.planner import precompile as precompile_planner
    from viapath.safety.shield import precompile as precompile_shield

    shield_ready = precompile_shield()  # first: the planner's warm-up cycles are checked by a shield
    return precompile_planner() and shield_ready
