"""The benchmark: generated scenario suites, ETH/UCY replays, a parallel runner and its report.

Nothing in the core (geometry, path, planning, sim) imports this package.
"""
