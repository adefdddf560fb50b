"""Within one cycle of a shielded planner the shield tests a single command once (the planner's test of
its chosen command is the filter's first test): the decisions are those of testing it twice."""

from __future__ import annotations

import contextlib

from hypothesis import HealthCheck, given, settings

from tests.planning.test_compiled_choice import PATHS, _observations, cases
from viapath.planning import make_planner
from viapath.safety.shield import Shield
from viapath.safety.shielded import ShieldedPlanner


@settings(max_examples=300, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(cases())
def test_remembered_verdicts_decide_as_fresh_ones(case):
    path = PATHS[case[0]]
    remembering = ShieldedPlanner(make_planner("viapath", path, nominal_speed_mps=0.2))
    fresh = ShieldedPlanner(make_planner("viapath", path, nominal_speed_mps=0.2))
    fresh.shield.remembering = contextlib.nullcontext  # every test computed again
    tests = {"remembering": 0, "fresh": 0}
    for name, planner in (("remembering", remembering), ("fresh", fresh)):
        evaluate = planner.shield._evaluate

        def counted(observation, commands, evaluate=evaluate, name=name):
            tests[name] += 1
            return evaluate(observation, commands)

        planner.shield._evaluate = counted
    for observation in _observations(case):
        a, b = remembering.plan(observation), fresh.plan(observation)
        assert a.command == b.command
        assert a.plan.status == b.plan.status
        assert a.plan.extras["shield"] == b.plan.extras["shield"]
        assert a.plan.extras.get("outside_shield") == b.plan.extras.get("outside_shield")
    assert tests["remembering"] <= tests["fresh"]


def test_verdicts_are_forgotten_after_the_cycle():
    shield = Shield()
    with shield.remembering():
        assert shield._verdicts == {}
    assert shield._verdicts is None
