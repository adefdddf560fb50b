"""Load scenarios from built-in names or YAML files, turning every failure into one clear message."""

from __future__ import annotations

from collections.abc import Mapping
from importlib import resources
from pathlib import Path
from typing import Any

import yaml
from pydantic import ValidationError

from viapath.io.safe_read import MAX_YAML_BYTES, InputError, load_yaml, read_text_file, short_repr
from viapath.options import OptionError
from viapath.scenarios.models import Scenario

_BUILTIN_PACKAGE = "viapath.scenarios.builtin"
_UNION_TAGS = {"moving", "replay", "segment", "spec"}


class _DuplicateKey(yaml.YAMLError):
    def __init__(self, key, line: int, first_line: int):
        super().__init__(f"duplicate key {key!r}")
        self.key, self.line, self.first_line = key, line, first_line


_SafeLoader: Any = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


class _UniqueKeyLoader(_SafeLoader):
    """PyYAML's safe loader, refusing a mapping that gives a key twice (PyYAML keeps the last silently).

    On libyaml's parser where PyYAML has it (a 1000-scenario suite spent most of a minute
    in the pure-Python parser); the constructor, hence the data, is the same either way."""

    def construct_mapping(self, node, deep=False):
        seen: dict = {}
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=deep)
            try:
                hash(key)
            except TypeError:
                continue  # the base class reports unhashable keys
            if key in seen:
                raise _DuplicateKey(key, key_node.start_mark.line + 1, seen[key])
            seen[key] = key_node.start_mark.line + 1
        return super().construct_mapping(node, deep=deep)


class ScenarioError(ValueError):
    """A scenario that cannot be used; the message names the file, the field and what was expected."""


def builtin_names() -> list[str]:
    files = resources.files(_BUILTIN_PACKAGE).iterdir()
    return sorted(f.name[: -len(".yaml")] for f in files if f.name.endswith(".yaml"))


def _builtin_text(name: str) -> str:
    return resources.files(_BUILTIN_PACKAGE).joinpath(f"{name}.yaml").read_text()


def load_scenario(source: str | Path) -> Scenario:
    """A built-in name (see :func:`builtin_names`) or the path of a YAML file."""
    source_str = str(source)
    if source_str in builtin_names():
        return _parse(_builtin_text(source_str), f"<built-in {source_str}>", base_dir=None)
    path = Path(source_str)
    if not path.exists():
        raise ScenarioError(
            f"{source_str}: no such file and no built-in scenario of that name "
            f"(built-ins: {', '.join(builtin_names())})"
        )
    if path.is_dir():
        raise ScenarioError(f"{source_str}: is a folder, expected a scenario YAML file")
    try:
        text = read_text_file(path, MAX_YAML_BYTES, "scenario YAML file")
    except InputError as error:
        raise ScenarioError(str(error)) from None
    return _parse(text, source_str, base_dir=path.parent)


MAX_REPORTED_ERRORS = 20  # field errors listed in one message; the rest are counted


def scenario_from_dict(data: dict[str, Any], origin: str = "<dict>") -> Scenario:
    """Every field error is reported (up to :data:`MAX_REPORTED_ERRORS`), the planner block's too."""
    try:
        scenario = Scenario.model_validate(data)
    except ValidationError as error:
        lines = format_validation_error(error, origin).splitlines()
        lines += _planner_block_errors(data, origin) if not any(": planner" in line for line in lines) else []
        raise ScenarioError(_capped(lines)) from None
    try:
        planner_settings(scenario)
    except (KeyError, OptionError) as error:
        raise ScenarioError(_capped(_planner_error(error, origin).splitlines())) from None
    return _without_retired_planner_options(scenario)


def _without_retired_planner_options(scenario: Scenario) -> Scenario:
    """The scenario without the planner block's retired names: they were read, with their warning, by the check
    above; the planner made from the scenario later need not read (and warn about) them again."""
    from viapath.planning import planner_class
    from viapath.scenarios.models import PlannerSpec

    spec = scenario.planner
    retired = planner_class(spec.name).options.retired
    if not any(name in retired for name in spec.given()):
        return scenario
    kept = {name: value for name, value in spec.given().items() if name not in retired}
    return scenario.model_copy(update={"planner": PlannerSpec.model_validate({"name": spec.name, **kept})})


def _planner_block_errors(data: Any, origin: str) -> list[str]:
    """The planner block's own errors, when the rest of the scenario has some too."""
    from viapath.scenarios.models import PlannerSpec

    block = data.get("planner") if isinstance(data, dict) else None
    if not isinstance(block, dict):
        return []
    try:
        spec = PlannerSpec.model_validate(block)
        from viapath.planning import planner_class

        planner_class(spec.name).options.validate(_with_preset(spec.given(), spec.name), where="planner")
    except (ValidationError, KeyError, OptionError) as error:
        if isinstance(error, ValidationError):
            return []  # the scenario model reported it
        return _planner_error(error, origin).splitlines()
    return []


def _capped(lines: list[str]) -> str:
    if len(lines) <= MAX_REPORTED_ERRORS:
        return "\n".join(lines)
    return "\n".join([*lines[:MAX_REPORTED_ERRORS], f"... and {len(lines) - MAX_REPORTED_ERRORS} more errors"])


def planner_settings(scenario: Scenario, planner_name: str | None = None) -> Mapping[str, Any]:
    """The options the scenario's ``planner:`` block sets, validated by the planner it names.

    The block configures the planner it names; another planner (``--planner``) runs with its own
    defaults. Raises ``KeyError`` for an unknown planner, :class:`OptionError` for a bad option."""
    from viapath.planning import planner_class

    spec = scenario.planner
    cls = planner_class(spec.name)  # KeyError names the available planners
    settings = cls.options.validate(_with_preset(spec.given(), spec.name), where="planner")
    return settings if planner_name in (None, spec.name) else {}


def _with_preset(given: dict[str, Any], planner_name: str) -> dict[str, Any]:
    """``weights: PRESET`` (a preset name or file, :mod:`viapath.presets`) → the preset's values; any
    other option the block gives beside it wins over the preset's."""
    if not isinstance(given.get("weights"), str):
        return given
    from viapath.presets import PresetError, load_preset

    try:
        preset = load_preset(given["weights"])
    except PresetError as error:
        raise OptionError([("planner.weights", str(error).replace("\n", "; "))]) from None
    if preset.planner != planner_name:
        raise OptionError(
            [("planner.weights", f"preset {preset.name!r} is for planner {preset.planner!r}, not {planner_name!r}")]
        )
    rest = {key: value for key, value in given.items() if key != "weights"}
    merged = preset.nested()
    for key, value in rest.items():
        merged[key] = (
            {**merged[key], **value} if isinstance(value, dict) and isinstance(merged.get(key), dict) else value
        )
    return merged


def _planner_error(error: Exception, origin: str) -> str:
    if isinstance(error, OptionError):
        return "\n".join(f"{origin}: {field}: {message}" for field, message in error.errors)
    return (
        f"{origin}: planner.name: {short_repr(error.args[0]) if not isinstance(error.args[0], str) else error.args[0]}"
    )


def _parse(text: str, origin: str, base_dir: Path | None) -> Scenario:
    try:
        data = load_yaml(text, origin, _UniqueKeyLoader)
    except _DuplicateKey as error:
        raise ScenarioError(
            f"{origin}: line {error.line}: duplicate key {short_repr(error.key)} (first given on line "
            f"{error.first_line}); each field may appear once"
        ) from None
    except InputError as error:
        raise ScenarioError(str(error)) from None
    if data is None and not any(line.strip() and not line.lstrip().startswith("#") for line in text.splitlines()):
        raise ScenarioError(
            f"{origin}: the file is empty; expected a mapping of scenario fields (name, robot, path, ...)"
        )
    if not isinstance(data, dict):
        raise ScenarioError(
            f"{origin}: expected a mapping of scenario fields (name, robot, path, ...), "
            f"found {'null' if data is None else type(data).__name__}"
        )
    scenario = scenario_from_dict(data, origin)
    if base_dir is not None:
        # Replay files are relative to the scenario file, so a suite folder can move as a whole.
        for item in scenario.obstacles:
            replay = getattr(item, "replay", None)
            if replay is not None and not Path(replay.file).is_absolute():
                candidate = base_dir / replay.file
                if candidate.exists() or not Path(replay.file).exists():
                    # Missing either way: name the resolved path, relative to the scenario file.
                    replay.file = str(candidate.resolve())
    return scenario


def format_validation_error(error: ValidationError, origin: str) -> str:
    lines = []
    for item in error.errors(include_url=False):
        location = ".".join(str(part) for part in _without_union_tags(item["loc"])) or "(top level)"
        message = item["msg"]
        found = item.get("input")
        found_text = "" if item["type"] in ("missing",) or isinstance(found, dict) else f"; found {short_repr(found)}"
        if item["type"] == "value_error":
            message = message.removeprefix("Value error, ")  # a validator's own sentence
        elif item["type"] == "extra_forbidden":
            message = "unknown field (check the spelling; extra fields are not allowed)"
        elif item["type"] == "missing" and item["loc"] and isinstance(item["loc"][-1], int):
            # A list too short for a fixed-size tuple such as a point [x, y]: name the whole list.
            location = location.rsplit(".", 1)[0]
            message = "too few items (a point is [x, y], a velocity [vx, vy], a wall [[x, y], [x, y]])"
            found_text = f"; found {short_repr(found)}"
        elif item["type"] == "missing":
            message = "required field is missing"
        elif item["type"] in ("too_long", "tuple_type"):
            message = "expected a list of 2 items: a point [x, y], a velocity [vx, vy], a wall [[x, y], [x, y]]"
        lines.append(f"{origin}: {location}: {message}{found_text}")
    return "\n".join(dict.fromkeys(lines))  # a list too short by two items gives the same line twice


def _without_union_tags(loc: tuple) -> list:
    """Drop the tag pydantic inserts after a list index for the tagged unions (obstacles, walls).

    Only a tag right after an index is dropped: ``replay`` is also a real field name
    (``obstacles.1.replay.file``), which must stay in the path.
    """
    return [part for i, part in enumerate(loc) if not (part in _UNION_TAGS and i > 0 and isinstance(loc[i - 1], int))]
