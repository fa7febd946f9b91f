"""``blockstack.read_pddl``, ``solve_pddl`` and ``solve_all``: the planning competitions'
Blocks World problems from Python."""


import gymnasium
import pytest

import blockstack


def test_a_generated_problem_reads_with_its_towers_and_a_plan_that_reaches_its_goal(cli, tmp_path):
    cli("generate", "--blocks", 9, "--count", 1, "--seed", 4, "--shape", "ipc", "--out", tmp_path)
    p = blockstack.read_pddl(tmp_path / "p01.pddl")
    assert p["name"] == "blockstack-01" and p["domain"] == "blocksworld"
    assert p["blocks"] == [f"b{i}" for i in range(1, 10)]
    assert sorted(b for t in p["start"] for b in t) == list(range(9))
    assert sorted(b for t in p["goal"] for b in t) == list(range(9))
    # The plan is the CLI's, move for move; replayed here over towers to the goal.
    printed = cli("solve", "--pddl", tmp_path / "p01.pddl").splitlines()
    assert [line for line in printed if not line.startswith(";")] == p["plan"]
    below = {}
    for tower in p["start"]:
        for i, b in enumerate(tower):
            below[b] = tower[i - 1] if i else None
    index = {name: i for i, name in enumerate(p["blocks"])}
    for action in p["plan"]:
        words = action.strip("()").split()
        if words[0] in ("stack", "putdown"):
            below[index[words[1]]] = index[words[2]] if words[0] == "stack" else None
    for tower in p["goal"]:
        assert all(below[b] == (tower[i - 1] if i else None) for i, b in enumerate(tower))


def test_the_optimal_solver_proves_the_exact_solvers_cost_and_names_its_limits(cli, tmp_path):
    # CLI = Python for every solver is the conformance suite's (test_conformance.py).
    cli("generate", "--blocks", 10, "--count", 1, "--seed", 5, "--shape", "ipc", "--out", tmp_path)
    task = tmp_path / "p01.pddl"
    proven = blockstack.solve_pddl(task, solver="optimal", time_limit=30)
    assert proven["optimal"] and proven["cost"] == blockstack.solve_pddl(task, solver="exact")["cost"]
    c = proven["certificate"]
    assert 2 * (c["misplaced"] + c["forced"] + c["breakers"]) == proven["lower_bound"]
    with pytest.raises(ValueError, match="time limit is the optimal solver's"):
        blockstack.solve_pddl(task, solver="exact", time_limit=1)
    with pytest.raises(ValueError, match="unknown planner"):
        blockstack.solve_pddl(task, solver="greedy")


@pytest.mark.parametrize("path", [None, 3, b"p.pddl"])
def test_a_path_that_is_not_text_is_a_type_error(path):
    for call in (blockstack.read_pddl, blockstack.solve_pddl, blockstack.solve_all):
        with pytest.raises(TypeError, match="is a file name"):
            call(path)


def test_a_bad_file_is_a_value_error_naming_its_problem(tmp_path):
    bad = tmp_path / "bad.pddl"
    bad.write_text(
        "(define (problem p) (:domain blocksworld) (:objects b1 b2)\n"
        " (:init (arm-empty) (clear b1) (on b1 b2) (on-table b2) (on-table b1))\n"
        " (:goal (and (on-table b1))))"
    )
    with pytest.raises(ValueError, match="block b1 is placed twice in the init"):
        blockstack.read_pddl(bad)
    with pytest.raises(ValueError, match="missing.pddl"):
        blockstack.read_pddl(tmp_path / "missing.pddl")


def test_blocks_world_from_a_task_starts_every_episode_at_its_start(cli, tmp_path):
    cli("generate", "--view", "side", "--blocks", 9, "--count", 1, "--seed", 6, "--out", tmp_path)
    task = tmp_path / "p01.pddl"
    p = blockstack.read_pddl(task)
    env = gymnasium.make("blockstack/BlocksWorld-v0", pddl=str(task), backend="grid", obs="state")
    base = env.unwrapped
    assert (base.world.blocks, base.world.grid) == (9, (9, 10))
    starts = []
    for seed in (0, 1, None):
        env.reset(seed=seed)
        cells, held, _ = base.state()
        starts.append(cells)
        assert held is None
    assert starts[0] == starts[1] == starts[2]
    # The start is the task's: its towers, bottom to top, on columns 0, 1, ...
    towers = [[b for b, (x, _) in sorted(enumerate(starts[0]), key=lambda c: c[1][1]) if x == col] for col in range(9)]
    assert [t for t in towers if t] == p["start"]
    # The goal is the task's: the near-optimal plan from the start, carried out by the
    # gripper, ends the episode there.
    assert base.world.goal.split("/") == [",".join(map(str, t)) for t in p["goal"]]
    plan = blockstack.solve(
        starts[0], base.world.goal, grid=base.world.grid, solver="near-optimal", view="side", cost="steps"
    )
    for i, action in enumerate(plan):
        _, _, terminated, truncated, _ = env.step(action)
        assert terminated == (i == len(plan) - 1) and not truncated
    # Reset options still give another start.
    other = [(b, 0) for b in range(9)]
    env.reset(options={"cells": other})
    assert base.state()[0] == other
    env.reset()
    assert base.state()[0] == starts[0]
    # The class takes it too.
    assert blockstack.BlocksWorldEnv(pddl=task, backend="grid").world.blocks == 9


def test_blocks_world_refuses_a_bad_task_in_one_value_error(tmp_path):
    bad = tmp_path / "bad.pddl"
    bad.write_text("(define (problem p) (:domain blocksworld) (:objects b1 b2)\n (:init (arm-empty) (on b1 b2) (on b2 b1))")
    with pytest.raises(ValueError, match="bad.pddl"):
        gymnasium.make("blockstack/BlocksWorld-v0", pddl=bad)
    with pytest.raises(ValueError, match="missing.pddl"):
        blockstack.BlocksWorldEnv(pddl=tmp_path / "missing.pddl")
    with pytest.raises(ValueError, match="leave out blocks, goal"):
        blockstack.BlocksWorldEnv(pddl=bad, blocks=3, goal="0,1,2")
    with pytest.raises(ValueError, match="path of a PDDL problem"):
        blockstack.BlocksWorldEnv(pddl=3)


def test_blocks_world_refuses_a_task_already_solved_in_one_value_error(tmp_path):
    # Gymnasium's reset cannot return an episode that is already over; the plan is empty.
    done = tmp_path / "done.pddl"
    done.write_text(
        "(define (problem p) (:domain blocksworld) (:objects b1 b2)\n"
        " (:init (arm-empty) (clear b1) (on b1 b2) (on-table b2))\n"
        " (:goal (and (on b1 b2) (on-table b2))))"
    )
    assert blockstack.read_pddl(done)["plan"] == []
    with pytest.raises(ValueError, match="done.pddl: the task's start already meets its goal"):
        gymnasium.make("blockstack/BlocksWorld-v0", pddl=done)


FIXTURES = __import__("pathlib").Path(__file__).resolve().parent / "fixtures"


def test_solve_pddl_takes_the_domain_s_action_names_and_writes_the_plan_file(cli, tmp_path):
    problem, domain = FIXTURES / "problem-pick-up.pddl", FIXTURES / "domain-pick-up.pddl"
    plan_file = tmp_path / "plan.txt"
    solved = blockstack.solve_pddl(problem, domain=domain, plan_file=plan_file)
    assert solved["plan"][0].startswith(("(pick-up ", "(unstack ")), solved["plan"]
    assert any(a.startswith("(put-down ") for a in solved["plan"]), solved["plan"]
    assert plan_file.read_text() == solved["text"] == cli("solve", "--pddl", problem, "--domain", domain)
    with pytest.raises(ValueError, match="the action move is not supported|is not one of the 4-operator"):
        blockstack.solve_pddl(problem, domain=FIXTURES / "domain-gripper.pddl")
    with pytest.raises(ValueError, match="is also the input"):
        blockstack.solve_pddl(problem, domain=domain, plan_file=domain)
    with pytest.raises(TypeError, match="plan_file is a file name"):
        blockstack.solve_pddl(problem, plan_file=3)


def test_an_empty_goal_is_the_empty_plan_and_no_episode_as_a_met_goal_is(tmp_path):
    empty = tmp_path / "empty.pddl"
    empty.write_text(
        "(define (problem p) (:domain blocksworld) (:objects b1 b2)\n"
        " (:init (arm-empty) (clear b1) (on b1 b2) (on-table b2))\n"
        " (:goal (and)))"
    )
    assert blockstack.solve_pddl(empty)["plan"] == []
    with pytest.raises(ValueError, match="empty.pddl: the task's start already meets its goal \\(which places no block\\)"):
        gymnasium.make("blockstack/BlocksWorld-v0", pddl=empty)
