"""The paper's planner (Yamada, Sa, Ohya): variable-speed via-point search in x-y-t, inside the path
boundary. The recipe is :mod:`viapath.planning.viapath.planner`; each of its steps is a module here:
:mod:`.checks` (the situation), :mod:`.candidates` (the speed set and the via points),
:mod:`.critics` (Eq. 1), :mod:`.follow` (motion limits), :mod:`.escape`; the options in
:mod:`.options`. The via-point formula itself is :func:`viapath.geometry.via_times`.

The compiled steps live beside them, one module per step: :mod:`.legs` (leg contacts and the corridor),
:mod:`.via` (via points), :mod:`.tree` (the candidate tree), :mod:`.selection` (Eq. 1 and the choice),
:mod:`.rollout` (the roll-outs the follow step checks), :mod:`.escape_figures` (the escape's standing check and
scores); :mod:`.packing` packs a cycle's arrays for them and :mod:`.records` names their records' fields.
"""

from viapath.planning.viapath.options import VIAPATH_OPTIONS
from viapath.planning.viapath.planner import ViaPathConfig, ViaPathPlanner

__all__ = ["VIAPATH_OPTIONS", "ViaPathConfig", "ViaPathPlanner"]
