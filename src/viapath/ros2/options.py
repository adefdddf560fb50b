"""The planner's option schema as the ROS 2 node sees it: one :class:`Option` per tunable value.

Source: the option schema of the planning redesign (``viapath.options``: an ``Option`` with
``name, default, unit, minimum, maximum, help, choices``; each planner class exposes
``planner_class(name).options``). Until that module is on main this file builds the same shape from
:class:`viapath.planning.viapath.ViaPathConfig` (an adapter): switching is the one line marked
``SWITCH`` below.

What we chose where the schema is silent:
* Units and bounds of the adapter come from the field names (``_m`` metres, ``_s`` seconds,
  ``_mps`` m/s, ``_rad`` radians) and from the checks of ``ViaPathConfig``/``PlannerSpec``; a
  weight or count without a physical unit has unit ``""``.
* Nested values (the weights of Eq. 1) are flattened with dots: ``weights.k1``.
* Options the node cannot set meaningfully (``record_candidates``) are left out.
"""

from __future__ import annotations

from dataclasses import MISSING, dataclass, fields
from typing import Any

try:  # SWITCH: when viapath.options lands on main, this import is the schema and the fallback goes.
    from viapath.options import Option  # type: ignore[import-not-found]
except ImportError:  # pragma: no cover - depends on the branch

    @dataclass(frozen=True)
    class Option:
        """One tunable value: name, default, SI unit, inclusive bounds (None = open), help, choices."""

        name: str
        default: Any
        unit: str = ""
        minimum: float | None = None
        maximum: float | None = None
        help: str = ""
        choices: tuple[str, ...] | None = None


_HELP = {
    "speeds_mps": "candidate speeds of the via-point search (paper: 0.1 ... 0.5 m/s)",
    "theta_unit": "unit of the heading term of E (radians by default; degrees swamp the others)",
    "planning_margin_m": "via points are computed on the disc grown by this much",
    "safety_margin_m": "legs are checked against the combined radius plus this",
    "horizon_s": "legs are checked for collisions up to this time ahead",
    "max_depth": "depth of the via-point chain (graph search)",
    "preferred_side": "side that wins near-ties (head-on case)",
    "hysteresis": "bonus of the previous cycle's way round (cost units of E)",
    "uncertainty_sigmas": "obstacles grow by this many velocity sigmas per second",
    "max_inflation_m": "cap of that growth",
    "side_tolerance": "cost the non-preferred side pays in a near-tie",
    "slow_times_s": "how long a candidate may first drive slower or stand",
    "rollout_heading_rad": "roll a plan out with the controller when its first leg turns more than this",
    "rollout_s": "length of that roll-out",
    "turn_in_place_min_rad": "a plan whose roll-out leaves the corridor turns on the spot first above this",
    "rollout_dt_s": "time step of the roll-out",
    "keep_previous_way": "re-check a way that vanished with less inflation and keep it if still cheaper",
    "keep_previous_inflation": "fraction of the inflation used for that re-check",
    "max_rollouts": "candidates tried, cheapest first, before falling back",
    "escape_s": "how long each escape command is rolled out",
    "escape_dt_s": "time step of the escape roll-out",
    "max_root_obstacles": "obstacles branched on at the root",
    "heading_gain": "steering gain towards the target (1/s)",
    "corridor_check_spacing_m": "spacing of the corridor check along a leg",
    "weights.k1": "weight of the path length in E (per metre)",
    "weights.k2": "weight of the travel time in E (per second)",
    "weights.k3": "weight of the speed change in E (per m/s)",
    "weights.k4": "weight of the heading change in E (per radian)",
}
_CHOICES = {"theta_unit": ("rad", "deg"), "preferred_side": ("left", "right")}
_INTEGER_BOUNDS = {"max_depth": (1, 6), "max_rollouts": (1, 100), "max_root_obstacles": (1, 1000)}
_LEFT_OUT = {"record_candidates"}


def _unit(name: str) -> str:
    for suffix, unit in (("_mps", "m/s"), ("_radps", "rad/s"), ("_rad", "rad"), ("_m", "m"), ("_s", "s")):
        if name.endswith(suffix):
            return unit
    return ""


def _viapath_options() -> tuple[Option, ...]:
    from viapath.planning.viapath import ViaPathConfig, Weights

    out = []
    for f in fields(ViaPathConfig):
        if f.name in _LEFT_OUT:
            continue
        if f.name == "weights":
            for w in fields(Weights):
                name = f"weights.{w.name}"
                out.append(Option(name, w.default, "", 0.0, None, _HELP.get(name, "")))
            continue
        default = f.default if f.default is not MISSING else f.default_factory()  # type: ignore[misc]
        if isinstance(default, str):
            out.append(Option(f.name, default, "", None, None, _HELP.get(f.name, ""), _CHOICES.get(f.name)))
        elif isinstance(default, bool):
            out.append(Option(f.name, default, "", None, None, _HELP.get(f.name, "")))
        elif isinstance(default, int):
            low, high = _INTEGER_BOUNDS.get(f.name, (0, None))
            out.append(Option(f.name, default, "", low, high, _HELP.get(f.name, "")))
        else:
            minimum = 0.0
            out.append(Option(f.name, default, _unit(f.name), minimum, None, _HELP.get(f.name, "")))
    return tuple(out)


def planner_options(planner_name: str) -> tuple[Option, ...]:
    """The option schema of a registered planner (its ``options`` attribute, or the adapter for ``viapath``)."""
    from viapath.planning import planner_class

    cls = planner_class(planner_name)
    options = getattr(cls, "options", None)
    if isinstance(options, tuple) and all(hasattr(o, "name") and hasattr(o, "default") for o in options):
        return options
    if planner_name == "viapath":
        return _viapath_options()
    return ()


def planner_kwargs(planner_name: str, values: dict[str, Any]) -> dict[str, Any]:
    """Keyword arguments for ``make_planner`` from option values (names as in :func:`planner_options`)."""
    from viapath.planning import planner_class

    cls = planner_class(planner_name)
    if hasattr(cls, "from_options"):  # the redesign's constructor, when it exists
        return {"config": cls.from_options(values)} if hasattr(cls, "config_from_options") else dict(values)
    if planner_name == "viapath":
        from viapath.planning.viapath import ViaPathConfig, Weights

        weights = Weights(**{k.split(".", 1)[1]: float(v) for k, v in values.items() if k.startswith("weights.")})
        rest = {k: v for k, v in values.items() if not k.startswith("weights.")}
        for key in ("speeds_mps", "slow_times_s"):
            if key in rest:
                rest[key] = tuple(float(x) for x in rest[key])
        return {"config": ViaPathConfig(weights=weights, **rest)}
    return dict(values)
