"""The laser chain's options as one typed schema: what a scenario's ``perception.options`` accepts.

Source: the dataclasses the chain is built from (:class:`~viapath.perception.scanner.ScannerModel`,
:class:`~viapath.perception.detection.DetectorParams` with its
:class:`~viapath.perception.segmentation.SegmentationParams`, :class:`~viapath.perception.tracking.TrackerParams`,
:class:`~viapath.perception.static_layer.StaticLayerParams`) and the keyword arguments of
:class:`~viapath.perception.laser.LaserPerception`. Each pydantic model here is generated from those fields and
defaults (a default is written once, in the dataclass or the signature); this module adds only what they do not
say: the bounds of a value with an obvious domain, and the allowed words of a choice.

Choices made here:
* Validation only, and a dump is the fields set: :meth:`LaserOptions.given` hands :class:`LaserPerception` exactly the fields the scenario set
  (nested as in YAML), so the objects built are the ones built from the same mapping before the schema existed.
* A model also builds its dataclass once, so a rule that spans fields (``range_min_m < range_max_m``,
  ``confirm_hits <= confirm_window``) is reported at load time with the field path, like a bound.
* An option that no longer does anything (:data:`~viapath.perception.detection.RETIRED_LASER_OPTIONS`: the
  choice between the numpy and the compiled code) is read with a FutureWarning and dropped.
"""

from __future__ import annotations

import dataclasses
import inspect
import math
import typing
from typing import Any, Literal

from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    SerializerFunctionWrapHandler,
    create_model,
    field_validator,
    model_serializer,
    model_validator,
)

from viapath.perception.detection import RETIRED_LASER_OPTIONS, DetectorParams
from viapath.perception.laser import LaserPerception
from viapath.perception.scanner import INVALID_ENCODINGS, ScannerModel
from viapath.perception.segmentation import SegmentationParams
from viapath.perception.static_layer import StaticLayerParams
from viapath.perception.tracking import TrackerParams

MAX_SCANNERS = 16  # scanners on one robot; each adds a scan to cast and segment every cycle
MAX_BEAMS = 100_000  # beams of one scanner (a URG-04LX has 683, a 0.1° 360° scanner 3600)
MAX_DISTANCE_M = 1.0e3  # m; ranges, radii and gaps of a 2-D laser chain are metres to tens of metres
MAX_DURATION_S = 3600.0  # s; memories and timeouts of the tracker and the static layer

_NonNegative: dict[str, Any] = {"ge": 0.0, "le": MAX_DISTANCE_M}
_Positive: dict[str, Any] = {"gt": 0.0, "le": MAX_DISTANCE_M}
_Duration: dict[str, Any] = {"gt": 0.0, "le": MAX_DURATION_S}
_Fraction: dict[str, Any] = {"ge": 0.0, "le": 1.0}

# Per dataclass: field name -> (bounds of pydantic's Field, annotation when not the dataclass's own).
_SCANNER: dict[str, dict[str, Any]] = {
    "name": {"min_length": 1, "max_length": 64},
    "mount_x_m": {"ge": -MAX_DISTANCE_M, "le": MAX_DISTANCE_M},
    "mount_y_m": {"ge": -MAX_DISTANCE_M, "le": MAX_DISTANCE_M},
    "mount_yaw_rad": {"ge": -2.0 * math.pi, "le": 2.0 * math.pi},
    "beam_count": {"ge": 2, "le": MAX_BEAMS},
    "angle_increment_rad": {"gt": 0.0, "le": math.pi},
    "range_min_m": _NonNegative,
    "range_max_m": _Positive,
    "scan_period_s": _Duration,
    "noise_sigma_near_m": _NonNegative,
    "noise_fraction_far": _Fraction,
    "noise_switch_range_m": _NonNegative,
}
_SEGMENTATION: dict[str, dict[str, Any]] = {
    "grazing_angle_rad": {"gt": 0.0, "le": 0.5 * math.pi},
    "noise_sigma_near_m": _NonNegative,
    "noise_fraction_far": _Fraction,
    "noise_switch_range_m": _NonNegative,
    "min_jump_m": _NonNegative,
    "max_gap_beams": {"ge": 0, "le": 1000},
    "min_points": {"ge": 2, "le": MAX_BEAMS},  # a circle fit needs two points (circle_fit.clusters_of)
}
_DETECTOR: dict[str, dict[str, Any]] = {
    "radius_prior_m": _Positive,
    "radius_prior_sigma_m": _Positive,
    "fixed_radius_m": _Positive,
    "radius_min_m": _NonNegative,
    "radius_max_m": _Positive,
    "max_extent_m": _Positive,
    "line_min_extent_m": _NonNegative,
    "line_max_sagitta_ratio": _NonNegative,
    "max_rms_m": _Positive,
    "occluded_max_sagitta_ratio": _NonNegative,
    "occluded_min_extent_m": _NonNegative,
    "flat_test_min_extent_m": _NonNegative,
    "duplicate_distance_m": _NonNegative,
    "leg_max_radius_m": _NonNegative,
    "leg_pair_distance_m": _NonNegative,
    "leg_position_sigma_m": _Positive,
    "measurement_sigma_floor_m": _NonNegative,
    "iterations": {"ge": 1, "le": 100},
}
_TRACKER: dict[str, dict[str, Any]] = {
    "acceleration_sigma_mps2": {"gt": 0.0, "le": 100.0},
    "initial_velocity_sigma_mps": {"gt": 0.0, "le": 100.0},
    "gate_chi2": {"gt": 0.0, "le": 1.0e6},
    "spawn_exclusion_m": _NonNegative,
    "track_merge_distance_m": _NonNegative,
    "track_merge_velocity_difference_mps": {"ge": 0.0, "le": 100.0},
    "gate_distance_m": _Positive,
    "confirm_hits": {"ge": 1, "le": 62},  # a track's hits are a bit mask of 62 cycles
    "confirm_window": {"ge": 1, "le": 62},
    "max_unseen_s": _Duration,
    "tentative_max_unseen_s": _Duration,
    "radius_smoothing": _Fraction,
    "static_after_s": {"gt": 0.0, "allow_inf_nan": True},  # .inf: a track never becomes static
    "static_radius_m": _Positive,
    "static_wake_speed_mps": {"gt": 0.0, "le": 100.0},
    "settled_acceleration_sigma_mps2": {"gt": 0.0, "le": 100.0},
    "settled_gate_chi2": {"gt": 0.0, "le": 1.0e6},
    "report_tentative_within_m": {"ge": 0.0, "le": 100.0},
}
_STATIC_LAYER: dict[str, dict[str, Any]] = {
    "explained_margin_m": _NonNegative,
    "link_m": _NonNegative,
    "step_m": _Positive,
    "memory_s": {"ge": 0.0, "le": MAX_DURATION_S},
    "see_through_m": _NonNegative,
    "merge_gap_m": _NonNegative,
}
_CHOICES: dict[str, Any] = {
    "invalid_encoding": Literal[INVALID_ENCODINGS],
}


class _Options(BaseModel):
    """A dataclass's options: unknown names, NaN and infinity refused; ``build()`` is the dataclass."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, ser_json_inf_nan="constants")
    built_from: typing.ClassVar[type]

    @model_serializer(mode="wrap")
    def _only_given(self, handler: SerializerFunctionWrapHandler) -> dict[str, Any]:
        """A dump holds what the input set, not the defaults: a scenario's content (and its hash) is what its file
        says, and a dump validated again sets the same fields."""
        return {name: value for name, value in handler(self).items() if name in self.model_fields_set}

    @model_validator(mode="before")
    @classmethod
    def _retired(cls, value: Any) -> Any:
        built_from = getattr(cls, "built_from", None)
        if isinstance(value, dict) and built_from in (DetectorParams, LaserPerception):
            where = "perception.options" + (".detector" if built_from is DetectorParams else "")
            return RETIRED_LASER_OPTIONS.drop(value, where, stacklevel=4)
        return value

    def given(self) -> dict[str, Any]:
        """The fields the input set (nested models as mappings), without the defaults."""
        return self.model_dump(exclude_unset=True)

    def build(self) -> Any:
        """The dataclass of these options (its defaults where none was given)."""
        values = {name: getattr(self, name) for name in self.model_fields_set}
        values = {name: value.build() if isinstance(value, _Options) else value for name, value in values.items()}
        return self.built_from(**values)

    @model_validator(mode="after")
    def _the_dataclass_accepts_them(self) -> _Options:
        self.build()  # its own checks (those that span fields): a ValueError here names this model's path
        return self


def _plain(default: Any) -> Any:
    """A default as JSON knows it (numpy's float64, e.g. ``np.deg2rad(10.0)``, as a float)."""
    return float(default) if isinstance(default, float) else default


def _model_of(
    name: str, cls: type, bounds: dict[str, dict[str, Any]], nested: dict[str, type[_Options]]
) -> type[_Options]:
    """A pydantic model with ``cls``'s fields, their types and defaults; ``bounds`` adds pydantic's limits."""
    hints = typing.get_type_hints(cls)
    fields: dict[str, Any] = {}
    for item in dataclasses.fields(cls):
        if item.name in nested:
            fields[item.name] = (nested[item.name], Field(default_factory=nested[item.name]))
            continue
        default = item.default if item.default is not dataclasses.MISSING else typing.cast(Any, item.default_factory)()
        annotation = _CHOICES.get(item.name, hints[item.name])
        fields[item.name] = (annotation, Field(_plain(default), **bounds.get(item.name, {})))
    doc = f"The fields of :class:`{cls.__module__}.{cls.__name__}`, with their defaults."
    model = create_model(name, __base__=_Options, __doc__=doc, **fields)
    model.built_from = cls
    return model


ScannerOptions = _model_of("ScannerOptions", ScannerModel, _SCANNER, {})
SegmentationOptions = _model_of("SegmentationOptions", SegmentationParams, _SEGMENTATION, {})
DetectorOptions = _model_of("DetectorOptions", DetectorParams, _DETECTOR, {"segmentation": SegmentationOptions})
TrackerOptions = _model_of("TrackerOptions", TrackerParams, _TRACKER, {})
StaticLayerOptions = _model_of("StaticLayerOptions", StaticLayerParams, _STATIC_LAYER, {})

# LaserPerception's keyword arguments -> (annotation, bounds); the defaults are the signature's.
_ARGUMENTS: dict[str, tuple[Any, dict[str, Any]]] = {
    "scanners": (list[ScannerOptions] | None, {"min_length": 1, "max_length": MAX_SCANNERS}),  # type: ignore[valid-type]
    "detector": (DetectorOptions | None, {}),
    "tracker": (TrackerOptions | None, {}),
    "range_noise": (bool, {}),
    "fixed_radius_m": (float | None, _Positive),
    "robot_radius_m": (float, _Positive),
    "mode": (Literal["laser"] | None, {}),
    "position_noise_m": (float | None, {}),
    "velocity_noise_mps": (float | None, {}),
    "static_layer": (StaticLayerOptions | None, {}),
}


class _LaserBase(_Options):
    """The keyword arguments of :class:`~viapath.perception.laser.LaserPerception`: scanners (default: the paper's
    two URG-04LX), detector, tracker, static layer, ray casting and range noise."""

    @field_validator("position_noise_m", "velocity_noise_mps", check_fields=False)
    @classmethod
    def _oracle_only(cls, value: float | None) -> float | None:
        if value not in (None, 0.0):
            raise ValueError("an oracle option: laser perception makes its own noise (range_noise); expected 0")
        return value

    def build(self) -> Any:
        return LaserPerception(**self.given())

    @model_validator(mode="after")
    def _the_dataclass_accepts_them(self) -> _LaserBase:
        return self  # each part was built by its own model; a LaserPerception is made when the run starts


def _laser_model() -> type[_Options]:
    fields: dict[str, Any] = {}
    for name, parameter in inspect.signature(LaserPerception).parameters.items():
        if parameter.kind is inspect.Parameter.VAR_KEYWORD:  # the retired options, dropped by _retired
            continue
        annotation, bounds = _ARGUMENTS[name]  # a new argument must be typed here
        fields[name] = (annotation, Field(parameter.default, **bounds))
    model = create_model("LaserOptions", __base__=_LaserBase, __doc__=_LaserBase.__doc__, **fields)
    model.built_from = LaserPerception
    return model


LaserOptions = _laser_model()
