"""viapath as a behaviour other simulators select by name: IR-SIM (``behavior: {name: viapath}``) and
navground (``behavior: {type: Viapath}``).

:mod:`viapath.integrations.host` is the part both share: the options a simulator's YAML may give (the
planner's own schema, plus the path's corridor, a weights preset and the shield), and the driver that
turns one cycle of what the simulator knows into an :class:`~viapath.observation.Observation` and a
command through the shipped planner and shield. :mod:`~viapath.integrations.irsim` and
:mod:`~viapath.integrations.navground` register it with each simulator (extras ``irsim`` and
``navground``); importing either without its simulator raises ImportError naming the extra.
"""
