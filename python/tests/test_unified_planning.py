"""``blockstack.unified_planning``: blockstack as a Unified Planning Framework engine, on
problems UPF's own PDDL reader reads, its plans checked by UPF's own validator."""

import pathlib

import pytest

up = pytest.importorskip("unified_planning")

from unified_planning.engines import PlanGenerationResultStatus as Status  # noqa: E402
from unified_planning.io import PDDLReader  # noqa: E402
from unified_planning.shortcuts import (  # noqa: E402
    GE,
    Fluent,
    InstantaneousAction,
    IntType,
    OneshotPlanner,
    PlanValidator,
    Problem,
    get_environment,
)

import blockstack  # noqa: E402
from blockstack.unified_planning import BlockstackPlanner  # noqa: E402

FIXTURES = pathlib.Path(__file__).resolve().parent / "fixtures"

# The one line python/README.md documents.
get_environment().factory.add_engine("blockstack", "blockstack.unified_planning", "BlockstackPlanner")
get_environment().credits_stream = None


def read(domain, problem):
    return PDDLReader().parse_problem(str(FIXTURES / domain), str(FIXTURES / problem))


def solve(problem, **params):
    with OneshotPlanner(name="blockstack", params=params) as planner:
        return planner.solve(problem)


def valid(problem, plan):
    with PlanValidator(problem_kind=problem.kind, plan_kind=plan.kind) as validator:
        return validator.validate(problem, plan).status.name == "VALID"


@pytest.mark.parametrize(
    "domain, task, first",
    [("domain-pickup.pddl", "problem-pickup.pddl", "pickup"), ("domain-pick-up.pddl", "problem-pick-up.pddl", "pick-up")],
)
def test_both_spellings_are_planned_optimally_and_pass_the_validator(domain, task, first):
    problem = read(domain, task)
    result = solve(problem)
    assert result.status == Status.SOLVED_OPTIMALLY, result
    assert result.engine_name == "blockstack"
    names = {a.action.name for a in result.plan.actions}
    assert first in names, names
    assert valid(problem, result.plan)
    # The plan is the native module's, action for action, and its bound is met.
    native = blockstack.solve_pddl(FIXTURES / task, solver="optimal", domain=FIXTURES / domain)
    ours = [" ".join([a.action.name, *(str(p) for p in a.actual_parameters)]) for a in result.plan.actions]
    # (UPF's reader lower-cases the names, as PDDL ignores case.)
    assert ours == [a.strip("()").lower() for a in native["plan"]]
    assert result.metrics["lower_bound"] == str(native["lower_bound"]) == str(len(result.plan.actions))


def test_a_generated_task_is_proven_optimal_and_the_near_optimal_plan_is_satisficing(cli, tmp_path):
    # 20 blocks drawn uniformly: the optimal solver's certificate closes, the near-optimal
    # planner's plan costs more than its bound (checked against the CLI's report).
    cli("generate", "--view", "side", "--blocks", 20, "--count", 1, "--seed", 3, "--out", tmp_path)
    task = tmp_path / "p01.pddl"
    problem = read("domain-pickup.pddl", task)
    optimal = solve(problem)
    assert optimal.status == Status.SOLVED_OPTIMALLY and valid(problem, optimal.plan)
    with OneshotPlanner(name="blockstack", params={"solver": "near-optimal"}) as planner:
        with pytest.warns(UserWarning, match="the timeout is the optimal solver's time limit"):
            near = planner.solve(problem, timeout=5)
    assert near.status == Status.SOLVED_SATISFICING and valid(problem, near.plan)
    assert len(near.plan.actions) > len(optimal.plan.actions) == int(optimal.metrics["lower_bound"])
    assert near.metrics["cost"] != near.metrics["lower_bound"]


def test_a_problem_that_is_not_the_blocks_world_is_unsupported():
    result = solve(read("domain-gripper.pddl", "problem-gripper.pddl"))
    assert result.status == Status.UNSUPPORTED_PROBLEM and result.plan is None
    assert "not one of the 4-operator Blocks World's" in result.log_messages[0].message

    # The Blocks World's names with another action's effect: not the Blocks World either.
    problem = read("domain-pickup.pddl", "problem-pickup.pddl")
    teleport = InstantaneousAction("teleport")
    problem.add_action(teleport)
    result = solve(problem)
    assert result.status == Status.UNSUPPORTED_PROBLEM
    assert "the action teleport is not supported" in result.log_messages[0].message


def test_a_problem_of_another_kind_is_outside_the_supported_kind_and_unsupported():
    problem = Problem("numeric")
    counter = Fluent("counter", IntType(0, 10))
    problem.add_fluent(counter, default_initial_value=0)
    problem.add_goal(GE(counter, 3))
    assert not BlockstackPlanner.supports(problem.kind)
    # UPF's factory warns that the kind is not supported; the engine answers it unsupported.
    with pytest.warns(UserWarning, match="cannot establish whether blockstack can solve"):
        result = solve(problem)
    assert result.status == Status.UNSUPPORTED_PROBLEM and result.plan is None
    # An engine told to fail on its checks refuses it before planning.
    planner = BlockstackPlanner()
    planner.error_on_failed_checks = True
    with pytest.raises(up.exceptions.UPUsageError):
        planner.solve(problem)
