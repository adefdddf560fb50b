"""One definition of each option: name, default, unit, bounds, one line of help.

Source: navground's habit (every behaviour declares its properties once, with a description), and
Nav2's parameters with descriptions and ranges. Everything that configures a planner or the shield
is an :class:`Option` in an :class:`OptionSet`; scenario YAML, the CLI (``--option NAME=VALUE``), the
ROS 2 node's parameters and ``viapath planners NAME`` are all generated from that set, so a
default, a unit or a bound is written in one place.

Choices made here:
* The kind of an option is the kind of its default: ``bool``, ``int``, ``float``, ``str`` (then
  ``choices`` lists the allowed words) or a tuple of floats (a list in YAML, e.g. the speed set).
* ``group`` nests an option in YAML (``weights: {k1: 0.1}``) and in ROS 2 parameter names
  (``weights.k1``); the option's own ``name`` is unique within its set without the group.
* Validation goes through a pydantic model built from the set (``extra="forbid"``, no NaN or
  infinity), so errors read like every other scenario error: the field path, what was expected
  and what was found. A set refuses two options of the same name.
* ``former_names``: an option that was renamed still reads its old name (a YAML file, ``--option``),
  with a FutureWarning saying the new one; giving both is an error.
* :class:`Retired`: a name that is no longer an option, still read (a YAML file, ``--option``, a ROS 2
  parameter) and ignored, with one FutureWarning saying what replaced it or why it does nothing now. Every
  option set keeps its retired names in a :class:`RetiredNames` (an :class:`OptionSet`'s ``retired``, the laser
  chain's in :mod:`viapath.perception.detection`), the one place they are read, warned about and left out.
* ``decides``: False for an option that only chooses how the arithmetic runs (numpy or compiled), never
  what is decided; results are the same either way, so a run's identity leaves it out.
"""

from __future__ import annotations

import reprlib
import warnings
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, create_model

MAX_LIST_ITEMS = 64  # items of a list option (a speed set): each adds work to every cycle
MAX_FOUND_CHARS = 80  # characters of a bad value quoted in an error message

_SHORT = reprlib.Repr()
_SHORT.maxstring = _SHORT.maxother = MAX_FOUND_CHARS
_SHORT.maxlist = _SHORT.maxtuple = _SHORT.maxdict = _SHORT.maxset = 6
_SHORT.maxlevel = 3


def short_repr(value: Any) -> str:
    """``repr(value)`` cut to a few dozen characters and a few items per level: for error messages,
    whose input may be huge (a list of a million items, or an alias bomb's shared lists)."""
    try:
        return _SHORT.repr(value)
    except Exception:
        return f"<{type(value).__name__}>"


@dataclass(frozen=True)
class Option:
    """One tunable value: what it is called, its default, its unit and range, and what it does."""

    name: str
    default: Any
    help: str
    unit: str = ""  # SI unit ("m", "s", "m/s", "rad", "m/s²"), "" for a plain number
    minimum: float | None = None
    maximum: float | None = None
    exclusive_minimum: bool = False  # the value must be > minimum rather than >= minimum
    choices: tuple[str, ...] | None = None
    group: str | None = None  # YAML/ROS nesting, e.g. "weights"
    former_names: tuple[str, ...] = ()  # names it had before: still read, with a FutureWarning
    decides: bool = True  # False: it chooses how the same arithmetic runs, not what is decided

    @property
    def kind(self) -> type:
        if isinstance(self.default, tuple):
            return tuple
        return type(self.default)

    @property
    def path(self) -> str:
        """The dotted name used in YAML paths and ROS 2 parameters."""
        return f"{self.group}.{self.name}" if self.group else self.name

    def describe(self) -> str:
        """One line for help texts and ROS parameter descriptions: help, unit and range."""
        bounds = []
        if self.minimum is not None:
            bounds.append(f"{'>' if self.exclusive_minimum else '>='} {self.minimum:g}")
        if self.maximum is not None:
            bounds.append(f"<= {self.maximum:g}")
        if self.choices:
            bounds.append("one of " + ", ".join(self.choices))
        unit = f" [{self.unit}]" if self.unit else ""
        return f"{self.help}{unit}" + (f" ({'; '.join(bounds)})" if bounds else "")

    def _annotation(self) -> Any:
        if self.choices:
            return Literal[self.choices]
        if self.kind is tuple:
            return tuple[float, ...]
        return self.kind

    def pydantic_field(self) -> tuple[Any, Any]:
        """(annotation, pydantic Field) of this option: its kind, default, bounds and description."""
        limits: dict[str, Any] = {}
        if self.minimum is not None:
            limits["gt" if self.exclusive_minimum else "ge"] = self.minimum
        if self.maximum is not None:
            limits["le"] = self.maximum
        if self.kind is tuple:
            # Bounds apply to every element of a list option; an empty list is never meaningful.
            from typing import Annotated

            element: Any = Annotated[float, Field(**limits)] if limits else float
            return (
                tuple[element, ...],
                Field(self.default, min_length=1, max_length=MAX_LIST_ITEMS, description=self.describe()),
            )
        return (self._annotation(), Field(self.default, description=self.describe(), **limits))


@dataclass(frozen=True)
class Retired:
    """A name that is no longer an option: what it was called, and what replaced it or why it does nothing now."""

    name: str
    reason: str

    def message(self, field: str) -> str:
        """The FutureWarning's text, for the option given as ``field`` (its path where it was given)."""
        return f"{field}: option {self.name!r} no longer does anything ({self.reason}); it is ignored"


class RetiredNames(Mapping[str, Retired]):
    """The retired names of one option set, by name (a name given twice is refused)."""

    def __init__(self, retired: Iterable[Retired] = (), owner: str = ""):
        self.owner = owner
        self._retired: dict[str, Retired] = {}
        for item in retired:
            if item.name in self._retired:
                raise ValueError(f"retired name {item.name!r} is given twice{f' in {owner}' if owner else ''}")
            self._retired[item.name] = item

    def __getitem__(self, name: str) -> Retired:
        return self._retired[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._retired)

    def __len__(self) -> int:
        return len(self._retired)

    def __add__(self, other: RetiredNames) -> RetiredNames:
        return RetiredNames([*self.values(), *other.values()], owner=other.owner or self.owner)

    def drop(
        self, values: Mapping[str, Any], where: str = "", prefix: str = "", separator: str = ".", stacklevel: int = 2
    ) -> dict[str, Any]:
        """``values`` without the retired names (keys ``prefix + name``: ``planner.compute`` of the ROS 2
        parameters), with one FutureWarning for each one given, naming it as ``where + separator + key``."""
        kept: dict[str, Any] = {}
        for key, value in values.items():
            name = str(key)[len(prefix) :] if str(key).startswith(prefix) else None
            if name is not None and name in self._retired:
                field = f"{where}{separator}{key}" if where else str(key)
                warnings.warn(self._retired[name].message(field), FutureWarning, stacklevel=stacklevel + 1)
                continue
            kept[key] = value
        return kept


def _first_causes(items: list[Any]) -> list[Any]:
    """Pydantic's errors without the consequences: a list whose bad elements were dropped is also
    reported too short; the elements' own errors say it."""
    bad_elements = {tuple(item["loc"][:-1]) for item in items if item["loc"] and isinstance(item["loc"][-1], int)}
    return [item for item in items if not (item["type"] == "too_short" and tuple(item["loc"]) in bad_elements)]


class Settings(Mapping):
    """Every option's value, read-only, by key (``settings["k1"]``) or attribute (``settings.k1``)."""

    def __init__(self, values: Mapping[str, Any]):
        object.__setattr__(self, "_values", dict(values))
        # Planners read their options as attributes every cycle: kept in the instance's own dict too, so a
        # read is one lookup, not a failed one and then __getattr__. Names the class has (keys, get, ...) stay
        # the class's, as with __getattr__ alone.
        cls = type(self)
        self.__dict__.update(
            (name, value)
            for name, value in self._values.items()
            if isinstance(name, str) and not name.startswith("_") and not hasattr(cls, name)
        )

    def __getattr__(self, name: str) -> Any:
        if name == "_values":  # asked before __init__ ran (copy and pickle make instances without it)
            raise AttributeError(name)
        try:
            return self._values[name]
        except KeyError:
            raise AttributeError(name) from None

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError("settings are read-only; build new ones with replace()")

    def __getitem__(self, name: str) -> Any:
        return self._values[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._values)

    def __len__(self) -> int:
        return len(self._values)

    def __repr__(self) -> str:
        return f"Settings({self._values!r})"

    def replace(self, **changes: Any) -> Settings:
        return Settings({**self._values, **changes})


class OptionError(ValueError):
    """A value that no option accepts; ``errors`` holds (field path, message) pairs."""

    def __init__(self, errors: list[tuple[str, str]]):
        self.errors = errors
        super().__init__("; ".join(f"{where}: {message}" if where else message for where, message in errors))


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, strict=False)


MAX_STEPS_PER_ROLLOUT = 2000  # a duration over its time step: bounds the work and memory of one cycle


class OptionSet:
    """An ordered set of options with unique names; validates nested (YAML) or flat mappings.

    ``steps`` pairs a duration option with its time step (``("rollout_s", "rollout_dt_s")``): each value
    is inside its own bounds, and together they must not make more than :data:`MAX_STEPS_PER_ROLLOUT`
    steps, else one cycle's roll-out would take unbounded time and memory."""

    def __init__(
        self,
        options: Iterable[Option],
        owner: str = "",
        steps: Iterable[tuple[str, str]] = (),
        retired: Iterable[Retired] = (),
    ):
        self.owner = owner  # e.g. the planner's name, for messages
        self.steps = tuple(steps)
        self.retired = RetiredNames(retired, owner)  # names that are no longer options: read, warned about, ignored
        self._options: dict[str, Option] = {}
        self._former: dict[str, str] = {}  # a former name -> the option's name now
        for option in options:
            if option.name in self._options or option.name in self._former:
                raise ValueError(f"option {option.name!r} is defined twice{f' in {owner}' if owner else ''}")
            self._options[option.name] = option
            for former in option.former_names:
                if former in self._options or former in self._former:
                    raise ValueError(f"former name {former!r} of option {option.name!r} is taken")
                self._former[former] = option.name
        for name in self.retired:
            if name in self._options or name in self._former:
                raise ValueError(f"retired name {name!r} is an option's name{f' in {owner}' if owner else ''}")
        self._model = self._build_model()

    def __iter__(self) -> Iterator[Option]:
        return iter(self._options.values())

    def __len__(self) -> int:
        return len(self._options)

    def __contains__(self, name: str) -> bool:
        return name in self._options

    def __getitem__(self, name: str) -> Option:
        return self._options[name]

    def __add__(self, other: OptionSet) -> OptionSet:
        return OptionSet(
            [*self, *other],
            owner=other.owner or self.owner,
            steps=(*self.steps, *other.steps),
            retired=(self.retired + other.retired).values(),
        )

    @property
    def names(self) -> list[str]:
        return list(self._options)

    def defaults(self) -> dict[str, Any]:
        return {option.name: option.default for option in self}

    def _build_model(self) -> type[BaseModel]:
        groups: dict[str, dict[str, Any]] = {}
        top: dict[str, Any] = {}
        for option in self:
            (groups.setdefault(option.group, {}) if option.group else top)[option.name] = option.pydantic_field()
        for group, fields in groups.items():
            sub = create_model(f"{self.owner or 'Options'}_{group}", __base__=_Strict, **fields)
            top[group] = (sub, Field(default_factory=sub))
        return create_model(f"{self.owner or 'Options'}", __base__=_Strict, **top)

    def nest(self, flat: Mapping[str, Any]) -> dict[str, Any]:
        """Flat ``{name: value}`` (or dotted ``group.name``) → the nested YAML shape."""
        nested: dict[str, Any] = {}
        for key, value in flat.items():
            name = key.split(".")[-1]
            option = self._options.get(name)
            if option is not None and option.group and (key == name or key == option.path):
                nested.setdefault(option.group, {})[name] = value
            else:
                nested[key] = value
        return nested

    def validate(self, values: Mapping[str, Any] | None, where: str = "") -> Settings:
        """Check ``values`` (nested as in YAML, flat, or dotted) against the set; return every option's
        value, flat. Raises :class:`OptionError` naming each bad field, prefixed by ``where``."""
        nested = self.nest(self.current_names(values or {}, where))
        try:
            model = self._model.model_validate(nested)
        except ValidationError as error:
            raise OptionError([self._explain(item, where) for item in _first_causes(error.errors())]) from None
        flat: dict[str, Any] = {}
        for option in self:
            value = getattr(getattr(model, option.group), option.name) if option.group else getattr(model, option.name)
            flat[option.name] = tuple(float(v) for v in value) if option.kind is tuple else value
        errors = self._step_errors(flat, where)
        if errors:
            raise OptionError(errors)
        return Settings(flat)

    def current_names(self, values: Mapping[str, Any], where: str = "") -> dict[str, Any]:
        """``values`` (nested, flat or dotted) with each option's former name (``former_names``) replaced by
        its name now, with a FutureWarning for each; an :class:`OptionError` when both names are given. A retired
        name (``retired``) is left out, with a FutureWarning."""
        if not self._former and not self.retired:
            return dict(values)
        groups = {option.group for option in self if option.group}
        current: dict[str, Any] = {}
        for key, value in values.items():
            if key in groups and isinstance(value, Mapping):
                value = self.current_names(value, f"{where}.{key}" if where else key)
            prefix, _, name = str(key).rpartition(".")
            if name in self.retired:
                field = f"{where}.{key}" if where else str(key)
                warnings.warn(self.retired[name].message(field), FutureWarning, stacklevel=2)
                continue
            if name in self._former:
                now = self._former[name]
                renamed = f"{prefix}.{now}" if prefix else now
                field = f"{where}.{key}" if where else str(key)
                if renamed in values:
                    raise OptionError([(field, f"option {name!r} is now called {now!r}; give only {now!r}")])
                warnings.warn(
                    f"{field}: option {name!r} is now called {now!r}; read as {now!r} (write {now!r} instead)",
                    FutureWarning,
                    stacklevel=2,
                )
                key = renamed
            current[key] = value
        return current

    def _step_errors(self, flat: Mapping[str, Any], where: str) -> list[tuple[str, str]]:
        errors = []
        for duration, step in self.steps:
            steps = flat[duration] / flat[step]
            if steps > MAX_STEPS_PER_ROLLOUT:
                path = self[duration].path
                field = f"{where}.{path}" if where else path
                errors.append(
                    (
                        field,
                        f"{duration} / {step} = {flat[duration]:g} s / {flat[step]:g} s = {steps:,.0f} "
                        f"steps; at most {MAX_STEPS_PER_ROLLOUT:,} (shorten {duration} or raise {step})",
                    )
                )
        return errors

    def _explain(self, item: Mapping[str, Any], where: str) -> tuple[str, str]:
        location = ".".join(str(part) for part in item["loc"])
        field = f"{where}.{location}" if where else location
        if item["type"] == "extra_forbidden":
            owner = f"planner {self.owner!r} has" if self.owner else "known"
            return field, (
                f"unknown option {item['loc'][-1]!r}; {owner} options: "
                f"{', '.join(option.path for option in self) or 'none'}"
            )
        if item["type"] == "too_short":
            least = item.get("ctx", {}).get("min_length", 1)
            return (
                field,
                f"expected at least {least} value{'s' if least != 1 else ''}; found {short_repr(item.get('input'))}",
            )
        return field, f"{item['msg']}; found {short_repr(item.get('input'))}"
