"""The shield's search of the dynamic window when the planner's command fails: the wanted command closest to it
(the definitions are in :mod:`viapath.safety.shield`).

Compiled (:func:`viapath.jit.compiled`), and plain Python with ``NUMBA_DISABLE_JIT=1``. Choices:

* Candidates: the planner's command, the hardest braking, the planner's turn rate at each sampled speed, its
  speed at each sampled turn rate, then the ``samples`` × ``samples`` grid over the window one period
  reaches (np.linspace's values, bit for bit).
* Closest first: the squared distance of the reached (v, ω) to the planner's, each axis over its limit; ties
  to the slower command, then to the lower row (a stable sort).
* Tested in chunks of about ``chunk`` (``np.array_split``'s pieces), stopping after the first chunk that holds
  a wanted one: it holds the closest wanted one, and the closest admissible one if there is one.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from viapath.jit import compiled
from viapath.safety.sweep import Drive, Robot, achieved_first_period
from viapath.safety.verdicts import Corridor, Fields, Forecast, People, Statics, evaluate

CHUNK = 24  # candidates tested at once when the planner's command fails


class Found(NamedTuple):
    """What the search found."""

    reached: np.ndarray  # (K, 2) the candidates' achieved (v, ω); row 0 the planner's, row 1 the braking
    pick: int  # the closest wanted (friendly in passive-friendly mode, else admissible) row, -1: none
    passive_pick: int  # the closest admissible row of the first chunk that held one, -1: none
    tested: int  # candidates tested
    passing: int  # admissible among them


@compiled
def linspace(start: float, stop: float, num: int) -> np.ndarray:
    """np.linspace(start, stop, num) for num >= 2, bit for bit (i · step + start, the last one stop)."""
    out = np.empty(num)
    div = num - 1
    delta = stop - start
    step = delta / div
    for i in range(num):
        out[i] = i / div * delta + start if step == 0 else i * step + start
    out[num - 1] = stop
    return out


@compiled
def candidates(robot: Robot, drive: Drive, speed_mps: float, turn_rate_radps: float, samples: int) -> np.ndarray:
    """The candidate commands (2 + 2 n + n², 2) for the planner's (``speed_mps``, ``turn_rate_radps``)."""
    corners = np.empty((2, 2))
    corners[0, 0], corners[0, 1] = 0.0, -drive.max_turn_rate_radps
    corners[1, 0], corners[1, 1] = drive.max_speed_mps, drive.max_turn_rate_radps
    corners = achieved_first_period(corners, robot, drive)
    n = samples
    v = linspace(corners[0, 0], corners[1, 0], n)
    w = linspace(corners[0, 1], corners[1, 1], n)
    out = np.empty((2 + 2 * n + n * n, 2))
    out[0, 0], out[0, 1] = speed_mps, turn_rate_radps
    out[1, 0], out[1, 1] = 0.0, 0.0
    planner = achieved_first_period(out[:1], robot, drive)
    for i in range(n):
        out[2 + i, 0], out[2 + i, 1] = v[i], planner[0, 1]
        out[2 + n + i, 0], out[2 + n + i, 1] = planner[0, 0], w[i]
        for j in range(n):
            out[2 + 2 * n + i * n + j, 0], out[2 + 2 * n + i * n + j, 1] = v[i], w[j]
    return out


@compiled
def closest_first(reached: np.ndarray, drive: Drive) -> np.ndarray:
    """The rows but the planner's own (row 0), closest to it first (a stable insertion sort)."""
    k_count = reached.shape[0]
    scale_v, scale_w = max(drive.max_speed_mps, 1e-9), max(drive.max_turn_rate_radps, 1e-9)
    distance = np.empty(k_count)
    for k in range(k_count):
        a = (reached[k, 0] - reached[0, 0]) / scale_v
        b = (reached[k, 1] - reached[0, 1]) / scale_w
        distance[k] = a * a + b * b
    order = np.empty(k_count - 1, dtype=np.int64)
    for k in range(1, k_count):
        i = k - 1  # the rows sorted so far
        while i > 0:
            o = order[i - 1]
            if distance[o] > distance[k] or (distance[o] == distance[k] and reached[o, 0] > reached[k, 0]):
                order[i] = o
                i -= 1
            else:
                break
        order[i] = k
    return order


@compiled
def search(
    robot: Robot,
    drive: Drive,
    forecast: Forecast,
    command: tuple[float, float],
    samples: int,
    people: People,
    statics: Statics,
    corridor: Corridor,
) -> Found:
    """The window search for the planner's (clipped) ``command`` (v, ω), which failed the test."""
    commands = candidates(robot, drive, command[0], command[1], samples)
    reached = achieved_first_period(commands, robot, drive)
    order = closest_first(reached, drive)
    total = order.shape[0]
    sections = max(1, (total + CHUNK - 1) // CHUNK)
    size, extra = total // sections, total % sections
    start, tested, passing, passive_pick = 0, 0, 0, -1
    for section in range(sections):
        length = size + 1 if section < extra else size
        rows = order[start : start + length]
        start += length
        verdicts = evaluate(robot, drive, forecast, commands[rows], people, statics, corridor)
        wanted = verdicts.friendly if forecast.friendly else verdicts.admissible
        tested += length
        passing += verdicts.admissible.sum()
        for i in range(length):
            if wanted[i]:
                return Found(reached, rows[i], passive_pick, tested, passing)
        for i in range(length):
            if passive_pick < 0 and verdicts.admissible[i]:
                passive_pick = rows[i]
    return Found(reached, -1, passive_pick, tested, passing)


@compiled
def search_fields(
    robot: Fields,
    drive: Fields,
    forecast: Fields,
    command: tuple[float, float],
    samples: int,
    people: Fields,
    statics: Fields,
    corridor: Fields,
) -> tuple[np.ndarray, int, int, int, int]:
    """:func:`search` called from Python: each record as its :data:`viapath.safety.verdicts.Fields`, the answer
    as a plain tuple in :class:`Found`'s order."""
    found = search(
        Robot(*robot),
        Drive(*drive),
        Forecast(*forecast),
        command,
        samples,
        People(*people),
        Statics(*statics),
        Corridor(*corridor),
    )
    return found.reached, found.pick, found.passive_pick, found.tested, found.passing
