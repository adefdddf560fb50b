"""Planners: the paper's (``viapath``) and baselines beside it, all behind one protocol."""

from viapath.planning.base import Decision, Plan, Planner, available_planners, make_planner, planner_class

__all__ = ["Decision", "Plan", "Planner", "available_planners", "make_planner", "planner_class"]
