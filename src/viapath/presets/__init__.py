"""Named sets of planner option values ("presets"), shipped as YAML and validated by the planner's schema.

Source: the weights k1..k4 of Eq. 1 (paper §4.2 and §5.2). A preset is a YAML file::

    name: close-to-path
    description: one line
    planner: viapath            # optional; the planner whose OptionSet validates the options
    options:                    # option values, nested as in a scenario's planner block
      weights: {k1: 0.2, k2: 0.01, k3: 0.08, k4: 0.3}   # or `weights: default`: the planner's defaults
    evidence: {...}             # free-form: the numbers that justify it (suite, seed, metrics)

Choices made (the issue is silent):
* Presets live beside the code as package data (``viapath/presets/*.yaml``); this loader does file I/O,
  so it sits outside the core (:mod:`viapath.planning` never imports it). A file path works wherever a
  preset name does; a name is tried first, then a path (a file called ``paper`` in the current folder
  does not shadow the shipped preset).
* A preset only sets the options it names; everything else keeps its default or the scenario's value.
  Where both give a value, the preset given on the command line wins over the scenario's block.
* Values are checked with the planner's :class:`~viapath.options.OptionSet` when loaded, so a bad
  preset fails with the file and the field before any episode runs.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import yaml

_PACKAGE = "viapath.presets"
_KEYS = {"name", "description", "planner", "options", "evidence"}


class PresetError(ValueError):
    """A preset that cannot be used; the message names the preset (or file), the field and what was expected."""


@dataclass(frozen=True)
class Preset:
    name: str
    description: str
    planner: str
    options: dict[str, Any]  # flat {option name: value}, only the options the preset sets, validated
    evidence: dict[str, Any] = field(default_factory=dict)
    source: str = ""  # "<built-in NAME>" or the file path

    def nested(self) -> dict[str, Any]:
        """The options nested as in a scenario's ``planner:`` block (``{"weights": {"k1": ...}}``)."""
        from viapath.planning import planner_class

        return planner_class(self.planner).options.nest(self.options)

    def dotted(self) -> dict[str, Any]:
        """The options keyed by their dotted path (``weights.k1``), as ROS 2 parameters name them."""
        from viapath.planning import planner_class

        schema = planner_class(self.planner).options
        return {schema[name].path: value for name, value in self.options.items()}

    def to_yaml(self) -> str:
        data = {
            "name": self.name,
            "description": self.description,
            "planner": self.planner,
            "options": _plain(self.nested()),
            "evidence": _plain(self.evidence),
        }
        return yaml.safe_dump(data, sort_keys=False, allow_unicode=True)


def _plain(value):
    """Tuples → lists and numpy scalars → Python numbers, so ``yaml.safe_dump`` takes them."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if hasattr(value, "item") and not isinstance(value, (str, bytes)):
        return value.item()
    return value


def preset_names() -> list[str]:
    files = resources.files(_PACKAGE).iterdir()
    return sorted(f.name[: -len(".yaml")] for f in files if f.name.endswith(".yaml"))


def load_preset(name_or_file: str | Path) -> Preset:
    """A shipped preset by name (:func:`preset_names`) or a preset YAML file."""
    text_name = str(name_or_file)
    if text_name in preset_names():
        text = resources.files(_PACKAGE).joinpath(f"{text_name}.yaml").read_text()
        return parse_preset(text, f"<built-in preset {text_name}>")
    path = Path(text_name)
    if not path.is_file():
        raise PresetError(f"{text_name}: not a preset name ({', '.join(preset_names())}) nor a preset file")
    from viapath.io.safe_read import MAX_YAML_BYTES, InputError, read_text_file

    try:
        text = read_text_file(path, MAX_YAML_BYTES, "preset YAML file")
    except InputError as error:
        raise PresetError(str(error)) from None
    return parse_preset(text, text_name)


def parse_preset(text: str, origin: str = "<preset>") -> Preset:
    from viapath.io.safe_read import InputError, load_yaml

    try:
        data = load_yaml(text, origin)
    except InputError as error:
        raise PresetError(str(error)) from None
    return preset_from_dict(data, origin)


def preset_from_dict(data: Any, origin: str = "<preset>") -> Preset:
    from viapath.options import OptionError
    from viapath.planning import available_planners, planner_class

    if not isinstance(data, dict):
        raise PresetError(f"{origin}: expected a mapping with name, description, options (and evidence)")
    unknown = sorted(set(data) - _KEYS)
    if unknown:
        raise PresetError(f"{origin}: {unknown[0]}: unknown field; a preset has {', '.join(sorted(_KEYS))}")
    name = data.get("name")
    if not isinstance(name, str) or not name.strip():
        raise PresetError(f"{origin}: name: expected a non-empty string, found {name!r}")
    planner = data.get("planner", "viapath")
    if planner not in available_planners():
        raise PresetError(
            f"{origin}: planner: unknown planner {planner!r}; available: {', '.join(available_planners())}"
        )
    options = data.get("options")
    if not isinstance(options, dict) or not options:
        raise PresetError(
            f"{origin}: options: expected a mapping of option values (e.g. weights: {{k1: 0.1}}), found {options!r}"
        )
    evidence = data.get("evidence") or {}
    if not isinstance(evidence, dict):
        raise PresetError(f"{origin}: evidence: expected a mapping, found {evidence!r}")
    schema = planner_class(planner).options
    try:
        options = _with_group_defaults(schema.current_names(options, where="options"), schema)
        settings = schema.validate(options, where="options")
    except OptionError as error:
        raise PresetError("\n".join(f"{origin}: {where}: {message}" for where, message in error.errors)) from None
    given = set(_flat_names(schema.nest(options)))
    return Preset(
        name=name,
        description=str(data.get("description") or ""),
        planner=planner,
        options={n: settings[n] for n in schema.names if n in given},
        evidence=evidence,
        source=origin,
    )


def _with_group_defaults(options: dict[str, Any], schema) -> dict[str, Any]:
    """``GROUP: default`` (e.g. ``weights: default``) → every option of that group at the planner's default."""
    groups = {option.group for option in schema if option.group}
    return {
        key: {o.name: o.default for o in schema if o.group == key} if key in groups and value == "default" else value
        for key, value in options.items()
    }


def _flat_names(nested: dict[str, Any]) -> list[str]:
    names: list[str] = []
    for key, value in nested.items():
        names.extend(value.keys() if isinstance(value, dict) else [key])
    return names


def preset_values(name_or_file: str | Path, planner: str = "viapath") -> dict[str, Any]:
    """The flat option values of a preset, for ``planner_overrides`` (the preset must be for ``planner``)."""
    preset = load_preset(name_or_file)
    if preset.planner != planner:
        raise PresetError(f"{name_or_file}: a preset for planner {preset.planner!r}, not {planner!r}")
    return dict(preset.options)


def all_presets() -> list[Preset]:
    return [load_preset(name) for name in preset_names()]
