"""Optimal assignment (linear sum assignment) without scipy, and gated association built on it.

Source: the shortest-augmenting-path algorithm of Jonker & Volgenant (Computing 38, 1987) in the
form of Crouse, "On implementing 2D rectangular assignment algorithms" (IEEE TAES 52(4), 2016) —
the one scipy.optimize.linear_sum_assignment uses. O(n³); the inner scan over columns is numpy.

What we chose for association (the source is about the assignment alone):
* Global nearest neighbour with a gate: a pair whose cost exceeds ``gate`` may not be matched, and
  leaving a track and a detection both unmatched costs ``gate`` — the classic augmented matrix, so
  the optimum never pairs two things farther apart than the gate just to pair more of them.
* The gated bipartite graph is split into connected components first: an isolated track–detection
  pair (by far the common case) is matched directly, and the O(n³) solver only sees the clusters
  where tracks compete for detections.
"""

from __future__ import annotations

import numpy as np

_FORBIDDEN = 1e12


def linear_sum_assignment(cost) -> tuple[np.ndarray, np.ndarray]:
    """Rows and columns of a minimum-cost complete matching of the smaller side (as scipy's).

    ``cost`` may hold ``inf`` for forbidden pairs; raises ``ValueError`` if no complete matching
    of the smaller side avoids them.
    """
    cost = np.asarray(cost, dtype=float)
    if cost.ndim != 2:
        raise ValueError("cost must be a 2-D array")
    if np.isnan(cost).any() or np.isneginf(cost).any():
        raise ValueError("cost contains NaN or -inf")
    transposed = cost.shape[0] > cost.shape[1]
    if transposed:
        cost = cost.T
    n_rows, n_cols = cost.shape
    if n_rows == 0:
        return np.zeros(0, dtype=int), np.zeros(0, dtype=int)
    u = np.zeros(n_rows)
    v = np.zeros(n_cols)
    col4row = np.full(n_rows, -1)
    row4col = np.full(n_cols, -1)
    for current in range(n_rows):
        sink, min_value, path, shortest, seen_rows, seen_cols = _shortest_augmenting_path(cost, u, v, row4col, current)
        u[current] += min_value
        others = seen_rows.copy()
        others[current] = False
        u[others] += min_value - shortest[col4row[others]]
        v[seen_cols] -= min_value - shortest[seen_cols]
        col = sink
        while True:
            row = int(path[col])
            row4col[col] = row
            col4row[row], col = col, int(col4row[row])
            if row == current:
                break
    rows = np.arange(n_rows)
    if transposed:
        order = np.argsort(col4row)
        return col4row[order], rows[order]
    return rows, col4row


def _shortest_augmenting_path(cost, u, v, row4col, current: int):
    """Dijkstra on the reduced costs from the free row ``current`` to the nearest free column (Crouse's shortest
    augmenting path): the column reached (``sink``), the path's length, the predecessor row of each column, the
    shortest distances and the rows and columns seen."""
    n_rows, n_cols = cost.shape
    shortest = np.full(n_cols, np.inf)
    path = np.full(n_cols, -1)
    seen_rows = np.zeros(n_rows, dtype=bool)
    seen_cols = np.zeros(n_cols, dtype=bool)
    row, min_value, sink = current, 0.0, -1
    while sink < 0:
        seen_rows[row] = True
        remaining = ~seen_cols
        reduced = min_value + cost[row] - u[row] - v
        better = remaining & (reduced < shortest)
        path[better] = row
        shortest[better] = reduced[better]
        candidates = np.flatnonzero(remaining)
        values = shortest[candidates]
        lowest = values.min()
        if not np.isfinite(lowest):
            raise ValueError("cost matrix is infeasible")
        ties = candidates[values == lowest]
        free = ties[row4col[ties] < 0]
        col = int(free[0] if len(free) else ties[0])
        min_value = lowest
        seen_cols[col] = True
        if row4col[col] < 0:
            sink = col
        else:
            row = int(row4col[col])
    return sink, min_value, path, shortest, seen_rows, seen_cols


def gated_assignment(cost, gate: float) -> list[tuple[int, int]]:
    """Pairs (row, col) of minimum total cost, each with ``cost <= gate``; leaving both unmatched costs ``gate``."""
    cost = np.asarray(cost, dtype=float)
    _n_rows, _n_cols = cost.shape
    allowed = np.isfinite(cost) & (cost <= gate)
    pairs: list[tuple[int, int]] = []
    if not allowed.any():
        return pairs
    if allowed.sum(0).max() <= 1 and allowed.sum(1).max() <= 1:
        # Every component is one isolated pair (the common case): those pairs, in row order, as below.
        rows, cols = np.nonzero(allowed)
        return list(zip(rows.tolist(), cols.tolist()))
    for rows, cols in _components(allowed):
        if len(rows) == 1 and len(cols) == 1:
            pairs.append((rows[0], cols[0]))
            continue
        sub = cost[np.ix_(rows, cols)]
        sub_allowed = allowed[np.ix_(rows, cols)]
        t, d = sub.shape
        big = np.full((t + d, d + t), _FORBIDDEN)
        big[:t, :d] = np.where(sub_allowed, sub, _FORBIDDEN)
        big[np.arange(t), d + np.arange(t)] = 0.5 * gate  # row left unmatched
        big[t + np.arange(d), np.arange(d)] = 0.5 * gate  # column left unmatched
        big[t:, d:] = 0.0
        r, c = linear_sum_assignment(big)
        for i, j in zip(r, c, strict=True):
            if i < t and j < d and sub_allowed[i, j]:
                pairs.append((rows[i], cols[j]))
    return sorted(pairs)


def _components(allowed: np.ndarray):
    """Connected components (rows, cols) of the bipartite graph given by the boolean matrix ``allowed``.

    Union–find over the allowed pairs in plain Python: the graphs are small and sparse.
    """
    n_rows = allowed.shape[0]
    parent = list(range(n_rows + allowed.shape[1]))

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    rows, cols = np.nonzero(allowed)
    for i, j in zip(rows.tolist(), cols.tolist(), strict=True):
        a, b = find(i), find(n_rows + j)
        if a != b:
            parent[b] = a
    groups: dict[int, tuple[list[int], list[int]]] = {}
    for i in sorted(set(rows.tolist())):
        groups.setdefault(find(i), ([], []))[0].append(i)
    for j in sorted(set(cols.tolist())):
        groups.setdefault(find(n_rows + j), ([], []))[1].append(j)
    return list(groups.values())
