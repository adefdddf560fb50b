"""numpy's pairwise summation, for compiled steps that must give numpy's sums bit for bit.

Source: numpy's ``pairwise_sum`` (``numpy/_core/src/umath/loops_utils.h.src``), which ``np.sum`` /
``np.add.reduce`` use along a contiguous axis: under 8 values one after the other, up to 128 in eight
running sums combined in pairs, more split in two halves at a multiple of 8. A kernel that adds a row
another way differs from numpy in the last bit now and then, and the decisions that rest on those sums
(the escape's separation, the laser detector's convexity test) must not.

Choices:
* The halving walks an explicit stack instead of recursing: the compiler's on-disk cache loads a self-recursive
  function that then crashes (segfault) in the next process.
* Used by the planner's escape (:mod:`viapath.planning.viapath.escape_figures`) and the laser detector's convexity
  test (:mod:`viapath.perception.detection`). The tests (``tests/planning/test_compiled_choice.py``) hold the sums
  to ``np.sum``, for 0 to 1 100 values.
"""

from __future__ import annotations

import numpy as np

from viapath.jit import compiled


@compiled
def _pairwise_block(values, start, count):
    """numpy's pairwise summation of at most 128 values: under 8 in order from -0.0, else eight running sums
    combined in pairs, then the rest in order."""
    if count < 8:
        total = -0.0
        for i in range(start, start + count):
            total += values[i]
        return total
    r0, r1, r2, r3 = values[start], values[start + 1], values[start + 2], values[start + 3]
    r4, r5, r6, r7 = values[start + 4], values[start + 5], values[start + 6], values[start + 7]
    limit = count - count % 8
    i = 8
    while i < limit:
        at = start + i
        r0 += values[at]
        r1 += values[at + 1]
        r2 += values[at + 2]
        r3 += values[at + 3]
        r4 += values[at + 4]
        r5 += values[at + 5]
        r6 += values[at + 6]
        r7 += values[at + 7]
        i += 8
    total = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < count:
        total += values[start + i]
        i += 1
    return total


@compiled
def pairwise_sum(values, start, count):
    """np.add.reduce of ``values[start:start + count]`` before its initial 0.0: numpy's pairwise summation
    along a contiguous axis (:func:`_pairwise_block`; more than 128 values split in halves at a multiple of
    8, each summed so, then added). numpy recurses; here the recursion is a stack of (start, count, stage),
    as the compiler's cache loads a self-recursive function that then crashes."""
    if count <= 128:
        return _pairwise_block(values, start, count)
    frame_start = np.empty(64, np.int64)
    frame_count = np.empty(64, np.int64)
    frame_stage = np.empty(64, np.int64)
    sums = np.empty(64)
    frames = 1
    held = 0
    frame_start[0] = start
    frame_count[0] = count
    frame_stage[0] = 0
    while frames:
        top = frames - 1
        first = frame_start[top]
        size = frame_count[top]
        half = size // 2
        half -= half % 8
        if size <= 128:
            sums[held] = _pairwise_block(values, first, size)
            held += 1
            frames -= 1
        elif frame_stage[top] == 0:  # the first half
            frame_stage[top] = 1
            frame_start[frames] = first
            frame_count[frames] = half
            frame_stage[frames] = 0
            frames += 1
        elif frame_stage[top] == 1:  # the second half
            frame_stage[top] = 2
            frame_start[frames] = first + half
            frame_count[frames] = size - half
            frame_stage[frames] = 0
            frames += 1
        else:  # both halves summed: their sum
            held -= 1
            sums[held - 1] = sums[held - 1] + sums[held]
            frames -= 1
    return sums[0]
