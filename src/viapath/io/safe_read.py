"""Bounded reading of input files, and the one YAML reader every part of viapath uses.

A scenario, preset, bench suite, path file or parameters file is read through :func:`load_yaml` or
:func:`read_yaml_file`; a trajectory file through :func:`read_text_file`. Each refuses, quickly and
with a short message naming the file (and the field where there is one), input that would take
unbounded time or memory:

* a file that is not a regular file (a device such as ``/dev/zero``, a FIFO) or is larger than a cap;
* YAML whose aliases expand to more nodes than a cap (a "billion laughs" bomb: a dozen lines that
  expand to a billion strings), nested deeper than a cap, or with more nodes than the cap;
* an integer literal with more digits than a 64-bit integer has (Python's ``int`` takes thousands of
  digits, and everything downstream then overflows).

The YAML is checked as a stream of parser events before any Python object is built, counting each
alias as the size of the node it repeats, so a bomb is refused after reading its few lines.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path
from typing import Any

import yaml

from viapath.options import short_repr

MAX_YAML_BYTES = 4 * 1024 * 1024  # B; the largest shipped scenario is a few kB
MAX_YAML_NODES = 50_000  # scalars and collections after alias expansion; a generated crowd scenario has ~5 000
MAX_YAML_DEPTH = 64  # nested mappings and lists
MAX_INT_DIGITS = 19  # a 64-bit integer
MAX_TEXT_BYTES = 64 * 1024 * 1024  # B; the largest ETH/UCY trajectory file is about 1.2 MB

_SAFE_LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
_INT_TAG = "tag:yaml.org,2002:int"
_RESOLVER = yaml.resolver.Resolver()


class InputError(ValueError):
    """Input refused before it is used; the message names the file (and the field), and what was expected."""


def read_bytes(path: str | Path, max_bytes: int, what: str = "file") -> bytes:
    """The content of a regular file of at most ``max_bytes``; :class:`InputError` otherwise (a folder,
    a device such as /dev/zero, a FIFO, a missing or unreadable file, a file that is too large)."""
    path = Path(path)
    try:
        info = os.stat(path)
    except OSError as error:
        raise InputError(f"{path}: cannot read {what}: {error.strerror or error}") from None
    if stat.S_ISDIR(info.st_mode):
        raise InputError(f"{path}: is a folder, expected a {what}")
    if not stat.S_ISREG(info.st_mode):
        raise InputError(f"{path}: not a regular file (a device, FIFO or socket); expected a {what}")
    if info.st_size > max_bytes:
        raise InputError(f"{path}: {info.st_size:,} bytes; a {what} may have at most {max_bytes:,}")
    try:
        with open(path, "rb") as handle:
            data = handle.read(max_bytes + 1)  # the file may have grown since stat
    except OSError as error:
        raise InputError(f"{path}: cannot read {what}: {error.strerror or error}") from None
    if len(data) > max_bytes:
        raise InputError(f"{path}: more than {max_bytes:,} bytes; a {what} may have at most {max_bytes:,}")
    return data


def read_text_file(path: str | Path, max_bytes: int = MAX_TEXT_BYTES, what: str = "file") -> str:
    """:func:`read_bytes` decoded as UTF-8."""
    data = read_bytes(path, max_bytes, what)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as error:
        raise InputError(f"{path}: cannot read {what}: not UTF-8 text (byte {error.start})") from None


def read_yaml_file(path: str | Path, what: str = "YAML file", loader: type | None = None) -> Any:
    """The data of a YAML file, bounded as :func:`load_yaml`; messages start with the path."""
    return load_yaml(read_text_file(path, MAX_YAML_BYTES, what), str(path), loader)


def load_yaml(text: str, origin: str = "<yaml>", loader: type | None = None) -> Any:
    """``yaml.safe_load(text)`` (or with ``loader``, a SafeLoader subclass) after checking the size,
    alias expansion, depth and integer literals (module notes). Raises :class:`InputError` for those
    and for text that is not YAML; other errors of ``loader`` (e.g. its own checks) pass through."""
    if len(text) > MAX_YAML_BYTES:
        raise InputError(f"{origin}: {len(text):,} characters; a YAML input may have at most {MAX_YAML_BYTES:,}")
    try:
        _check_events(text, origin)
        return yaml.load(text, Loader=loader or _SAFE_LOADER)
    except yaml.YAMLError as error:
        if not type(error).__module__.startswith("yaml"):
            raise  # a loader's own check (e.g. duplicate keys): the caller reports it
        mark = getattr(error, "problem_mark", None)
        where = f" line {mark.line + 1}, column {mark.column + 1}:" if mark else ""
        problem = getattr(error, "problem", None) or str(error)
        raise InputError(f"{origin}:{where} not valid YAML: {problem}") from None
    except RecursionError:
        raise InputError(f"{origin}: nested too deeply") from None


class _Frame:
    __slots__ = ("anchor", "expect_key", "index", "is_map", "key", "size")

    def __init__(self, anchor, is_map):
        self.anchor, self.size, self.is_map = anchor, 1, is_map
        self.expect_key, self.key, self.index = True, None, 0

    def label(self) -> str:
        return str(self.key) if self.is_map else str(self.index)


def _field(stack: list[_Frame]) -> str:
    return (
        ".".join(short_repr(f.label()).strip("'") for f in stack if not f.is_map or not f.expect_key) or "(top level)"
    )


def _check_events(text: str, origin: str) -> None:
    """Walk the parser's events: count nodes with aliases expanded, track depth and the field path."""
    parser = _SAFE_LOADER(text)
    try:
        anchors: dict[str, int] = {}
        stack: list[_Frame] = []
        total = 0
        get_event = parser.get_event
        while (event := get_event()) is not None:
            kind = type(event)
            if kind in (yaml.MappingStartEvent, yaml.SequenceStartEvent):
                stack.append(_Frame(event.anchor, kind is yaml.MappingStartEvent))
                if len(stack) > MAX_YAML_DEPTH:
                    raise InputError(
                        f"{origin}: {_field(stack[:-1])}: nested more than {MAX_YAML_DEPTH} levels deep "
                        f"(line {event.start_mark.line + 1})"
                    )
                total += 1
                continue
            elif kind in (yaml.MappingEndEvent, yaml.SequenceEndEvent):
                frame = stack.pop()
                if frame.anchor is not None:
                    anchors[frame.anchor] = frame.size
                if stack:
                    _advance(stack[-1], frame.size, None)
                continue
            elif kind is yaml.ScalarEvent:
                if event.anchor is not None:
                    anchors[event.anchor] = 1
                total += 1
                if len(event.value) > MAX_INT_DIGITS:
                    _check_scalar(event, stack, origin)
                size = 1
            elif kind is yaml.AliasEvent:
                size = anchors.get(event.anchor, 1)
                total += size
            else:
                continue
            if total > MAX_YAML_NODES:
                raise InputError(
                    f"{origin}: more than {MAX_YAML_NODES:,} values once aliases (*name) are expanded "
                    f"(at {_field(stack)}, line {event.start_mark.line + 1}); refused as too large "
                    "(an alias bomb or a file too big to be a viapath input)"
                )
            if stack:
                _advance(stack[-1], size, event.value if kind is yaml.ScalarEvent else None)
    finally:
        parser.dispose()


def _advance(frame: _Frame, size: int, scalar) -> None:
    frame.size += size
    if frame.is_map:
        if frame.expect_key:
            frame.key = scalar if scalar is not None else "<key>"
        frame.expect_key = not frame.expect_key
    else:
        frame.index += 1


def _check_scalar(event, stack: list[_Frame], origin: str) -> None:
    """Refuse an integer literal longer than a 64-bit integer (plain, or tagged ``!!int``)."""
    value = event.value
    if event.tag == _INT_TAG:
        is_int = True
    elif event.tag in (None, "!") and event.implicit[0] and not event.style:
        is_int = _RESOLVER.resolve(yaml.ScalarNode, value, (True, False)) == _INT_TAG
    else:
        is_int = False
    digits = sum(ch.isalnum() for ch in value) if is_int else 0
    if digits > MAX_INT_DIGITS:
        raise InputError(
            f"{origin}: {_field(stack)}: an integer of {digits:,} digits (line {event.start_mark.line + 1}); "
            f"expected a number of at most {MAX_INT_DIGITS} digits"
        )
