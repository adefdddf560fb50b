"""Compile viapath's compiled steps now (or load them from the on-disk cache), for a long run that should take
them from its first cycle: ``viapath bench`` before its workers start, the ROS 2 node before it makes its planner
and shield. The steps live with their features (the planner's in :mod:`viapath.planning.viapath`, the shield's in
:mod:`viapath.safety`), each decorated with :func:`viapath.jit.compiled`; with compilation off they run as plain
Python and this costs only the two warm-up runs (docs/explanation/speed.md).

It builds a planner and a shield and runs them, so it lives outside both.
"""

from __future__ import annotations

import sys


def precompile() -> bool:
    """The shield's compiled test, then the planner's steps (about a minute of CPU once per machine, said on
    stderr); True when both are ready."""
    from viapath.jit import first_compilation_note

    note = first_compilation_note()
    if note is not None:
        print(note, file=sys.stderr, flush=True)
    from viapath.planning.viapath.planner import precompile as precompile_planner
    from viapath.safety.shield import precompile as precompile_shield

    shield_ready = precompile_shield()  # first: the planner's warm-up cycles are checked by a shield
    return precompile_planner() and shield_ready
