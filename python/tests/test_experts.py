"""Every expert, by its one name, in each view: the names the top view lacks are refused by
``blockstack run --agent NAME`` and ``blockstack.demonstrations(expert=NAME)`` alike
(``agent::PolicyKind``). That both play the same actions in every world is the conformance
suite's (test_conformance.py)."""

import json

import pytest

import blockstack

EPISODES, SEED = 4, 5


def python_actions(view, expert, blocks, goal):
    d = blockstack.demonstrations(EPISODES, expert=expert, blocks=blocks, goal=goal, view=view, seed=SEED, backend="grid")
    episodes = {}
    for k, a in zip(d["episodes"].tolist(), d["actions"].tolist()):
        episodes.setdefault(k, []).append(a)
    return [episodes[k] for k in sorted(episodes)]


def test_exact_is_the_fewest_gripper_steps_in_the_side_view():
    """``exact`` means the fewest environment steps in both views; the fewest block moves
    are ``exact-moves``: never fewer steps, and more on some start."""
    exact = python_actions("side", "exact", 4, "1,3,2/")
    moves = python_actions("side", "exact-moves", 4, "1,3,2/")
    assert all(len(e) <= len(m) for e, m in zip(exact, moves))
    drops = lambda episode: sum(a == 4 for a in episode)  # noqa: E731 - Drop ends a block move
    assert all(drops(m) <= drops(e) for e, m in zip(exact, moves))


@pytest.mark.parametrize("expert", ["exact-moves", "near-optimal"])
def test_block_move_experts_are_refused_in_the_top_view_alike(cli, expert):
    with pytest.raises(ValueError) as python:
        blockstack.demonstrations(1, expert=expert)
    import subprocess

    with pytest.raises(subprocess.CalledProcessError) as run:
        cli("run", "--agent", expert, "--episodes", 1)
    assert str(python.value) in run.value.stderr
    assert run.value.stderr.count("\n") == 1


def test_an_unknown_expert_is_refused_with_the_planners_names():
    with pytest.raises(ValueError, match="choose one of exact, exact-moves, near-optimal, optimal, oracle"):
        blockstack.demonstrations(1, expert="human")
