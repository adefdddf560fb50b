"""The paper's planner (Yamada, Sa, Ohya): variable-speed via-point search in x-y-t, inside the path
boundary. The recipe is :mod:`viapath.planning.viapath.planner`; each of its steps is a module here:
:mod:`.checks` (the situation), :mod:`.candidates` (the speed set and the via points),
:mod:`.critics` (Eq. 1), :mod:`.follow` (motion limits), :mod:`.escape`; the options in
:mod:`.options`. The via-point formula itself is :func:`viapath.geometry.via_times`.
"""

from viapath.planning.viapath.options import VIAPATH_OPTIONS
from viapath.planning.viapath.planner import ViaPathConfig, ViaPathPlanner

__all__ = ["VIAPATH_OPTIONS", "ViaPathConfig", "ViaPathPlanner"]
