"""``blockstack.read_pddl``: the planning competitions' Blocks World problems from Python."""

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
    assert cli("solve", "--pddl", tmp_path / "p01.pddl").splitlines()[:-1] == p["plan"]
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
