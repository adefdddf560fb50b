"""What every command shares: the consoles, the one way to refuse input (a red ``error:`` line on
stderr, exit 2, no traceback) and the checks of output files and noise levels."""

from __future__ import annotations

import math
from collections.abc import Iterable
from pathlib import Path
from typing import NoReturn

import typer
from rich.console import Console
from rich.markup import escape

console = Console()
errors = Console(stderr=True)

PLOT_SUFFIXES = (".pdf", ".png", ".svg")
ANIMATION_SUFFIXES = (".gif", ".mp4")


def fail(message: str, code: int = 2) -> NoReturn:
    """Print ``error: message`` on stderr (markup in the message shown as typed) and exit with ``code``."""
    errors.print(f"[bold red]error:[/] {escape(message)}", highlight=False, soft_wrap=True)
    raise typer.Exit(code)


def note_first_compilation() -> None:
    """Say on stderr that this run compiles viapath's steps for this machine (once: later runs load them)."""
    from viapath.jit import first_compilation_note

    note = first_compilation_note()
    if note is not None:
        errors.print(note, highlight=False, soft_wrap=True, markup=False)


def compiled_or_plain() -> bool:
    """Before a command makes its first compiled step: compiled when this version's cache is ready; else, unless
    ``VIAPATH_BACKGROUND_COMPILE=0``, plain Python in this run while a background process fills the cache for
    the next runs (compiling first would cost this run about a minute; the plain run takes seconds). True when
    this run is plain for that reason: :func:`start_compiling` then starts the background process."""
    from viapath import jit

    if not jit.enabled() or jit.cache_is_ready():
        return False
    from viapath.precompile import background_allowed

    return background_allowed() and jit.run_plain()


def start_compiling(plain: bool) -> None:
    """Once the command's input is checked: start the background compilation (``plain``, from
    :func:`compiled_or_plain`) and say so in one line, or say that this run compiles (a cold cache, no
    background compilation)."""
    if not plain:
        note_first_compilation()
        return
    from viapath.precompile import COMPILE_CPU_S, start_in_background

    pid = start_in_background()
    errors.print(
        "viapath: this run uses plain Python; compiling viapath's planner, shield and laser chain in the "
        f"background for the next runs (about {COMPILE_CPU_S} s of CPU, pid {pid}; "
        "`viapath precompile` waits for it)",
        highlight=False,
        soft_wrap=True,
        markup=False,
    )


def check_output(file: Path | None, suffixes: Iterable[str], option: str) -> None:
    """Refuse an output file with another suffix, or in a folder that does not exist."""
    if file is None:
        return
    suffixes = tuple(suffixes)
    if file.suffix.lower() not in suffixes:
        fail(f"{option} {file}: expected a file ending in {', '.join(suffixes)}")
    if not file.parent.exists():
        fail(f"{option} {file}: folder {file.parent} does not exist")


def check_noise(value: float | None, option: str) -> None:
    if value is not None and (not math.isfinite(value) or value < 0):
        fail(f"{option}: expected a finite number >= 0, found {value}")


def caused_by_interrupt(error: BaseException | None) -> bool:
    """Whether a KeyboardInterrupt is behind ``error`` (the compiled code turns one raised while a compiled function
    calls back into Python, e.g. to unpickle a constant, into a chain of SystemErrors)."""
    seen = set()
    while error is not None and id(error) not in seen:
        if isinstance(error, KeyboardInterrupt):
            return True
        seen.add(id(error))
        error = error.__cause__ or error.__context__
    return False
