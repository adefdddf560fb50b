"""Registries by name (planners, perception modes, scenario families), refusing duplicates.

Source: navground's ``class X(Behavior, name="...")`` and IR-SIM's ``@register_behavior``: a thing
registers itself where it is defined, and the CLI, the schema and the reports take their lists from
the registry instead of lists kept by hand. A second entry under a taken name is an error: silently
replacing the first made a plug-in shadow a built-in without a word.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Generic, TypeVar

T = TypeVar("T")


class DuplicateNameError(ValueError):
    pass


class Registry(Generic[T]):
    """Name → entry. ``loader`` (optional) is called once before the first look-up, to import the
    modules whose definitions register themselves."""

    def __init__(self, kind: str, loader: Callable[[], None] | None = None):
        self.kind = kind
        self._entries: dict[str, T] = {}
        self._loader = loader
        self._loaded = loader is None

    def add(self, name: str, entry: T) -> T:
        if not name:
            raise ValueError(f"a {self.kind} needs a name")
        existing = self._entries.get(name)
        if existing is not None and existing is not entry:
            raise DuplicateNameError(
                f"{self.kind} {name!r} is already registered ({_describe(existing)}); refusing {_describe(entry)}"
            )
        self._entries[name] = entry
        return entry

    def register(self, name: str) -> Callable[[T], T]:
        """Decorator form: ``@FAMILIES.register("crossing")``."""
        return lambda entry: self.add(name, entry)

    def _load(self) -> None:
        if not self._loaded:
            self._loaded = True
            self._loader()  # type: ignore[misc]  # not loaded: there is a loader

    def names(self) -> list[str]:
        self._load()
        return sorted(self._entries)

    def ordered(self) -> list[str]:
        """The names in the order they were registered."""
        self._load()
        return list(self._entries)

    def get(self, name: str) -> T:
        self._load()
        try:
            return self._entries[name]
        except KeyError:
            raise KeyError(f"unknown {self.kind} {name!r}; available: {', '.join(sorted(self._entries))}") from None

    def __contains__(self, name: str) -> bool:
        self._load()
        return name in self._entries

    def __iter__(self) -> Iterator[str]:
        return iter(self.names())


def _describe(entry) -> str:
    module = getattr(entry, "__module__", None)
    qualname = getattr(entry, "__qualname__", None)
    return f"{module}.{qualname}" if module and qualname else repr(entry)
