"""``blockstack/BlocksWorld-v0``: the side view (towers on a table, gravity), goals of
several towers, block moves, and ``view=`` on the vector environment."""

import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import blockstack

ENV_ID = "blockstack/BlocksWorld-v0"


@pytest.mark.parametrize("backend", ["physics", "grid"])
@pytest.mark.parametrize("obs", ["planes", "frame", "state"])
def test_env_checker_passes_without_a_warning(backend, obs):
    env = gym.make(ENV_ID, blocks=4, goal="0,1/2", obs=obs, backend=backend, render_mode="ansi", disable_env_checker=True)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(env.unwrapped, skip_render_check=False)


def test_the_side_view_picks_only_clear_blocks_and_drops_them_onto_towers():
    env = gym.make(ENV_ID, blocks=3, goal="2,0,1", grid=(4, 4), backend="physics")
    # 0 on the table, 1 on 0, 2 on the table at column 2.
    _, info = env.reset(options={"cells": [(0, 0), (0, 1), (2, 0)]})
    assert list(np.flatnonzero(info["action_mask"])) == [6, 7]
    # Under the default free protocol an action outside the mask changes nothing.
    env.step(5)
    assert env.unwrapped.state()[1] is None
    for action in [6, 0, 3, 3, 3, 4]:  # pick 1, up, right x3, drop: it falls to the table
        env.step(action)
    assert env.unwrapped.state()[0][1] == (3, 0)
    for action in [5, 0, 3, 3, 4]:  # 0 onto 2
        env.step(action)
    *_, terminated, _, _ = env.step(6)
    for action in [0, 0, 2]:
        *_, terminated, _, _ = env.step(action)
        assert not terminated, "a held block stands on nothing"
    *_, terminated, _, _ = env.step(4)
    assert terminated


def test_block_moves_count_moves_and_gripper_steps():
    env = gym.make(ENV_ID, blocks=3, goal="2,0,1", grid=(4, 4), actions="moves")
    assert env.action_space.n == 3 * (3 + 4)
    _, info = env.reset(options={"cells": [(0, 0), (0, 1), (2, 0)]})
    per = 3 + 4

    def move(block, dest):
        return block * per + dest

    assert info["action_mask"][move(1, 2)] == 1 and info["action_mask"][move(0, 2)] == 0
    # A move from under another block changes nothing: one step, said to be illegal.
    _, _, _, _, info = env.step(move(0, 2))
    assert info["illegal"] and info["gripper_steps"] == 1 and env.unwrapped.state()[0] == [(0, 0), (0, 1), (2, 0)]
    strict = gym.make(ENV_ID, blocks=3, goal="2,0,1", grid=(4, 4), actions="moves", strict=True)
    strict.reset(options={"cells": [(0, 0), (0, 1), (2, 0)]})
    with pytest.raises(ValueError, match="block 1 stands on block 0"):
        strict.step(move(0, 2))
    _, _, _, _, info = env.step(move(1, 3 + 3))  # 1 onto the table at column 3
    assert info["gripper_steps"] == 5 and not info["illegal"]
    env.step(move(0, 2))  # 0 onto 2
    _, _, terminated, _, info = env.step(move(1, 0))  # 1 onto 0
    assert terminated and info["gripper_steps"] == 5
    with pytest.raises(ValueError, match='needs view="side"'):
        gym.make("blockstack/Stack-v0", actions="moves")


def test_seeded_starts_stand_and_follow_the_seed():
    a = gym.make(ENV_ID, blocks=5, backend="physics")
    b = gym.make(ENV_ID, blocks=5, backend="grid")
    for seed in range(10):
        (oa, _), (ob, _) = a.reset(seed=seed), b.reset(seed=seed)
        assert np.array_equal(oa, ob)
        cells, held, _ = a.unwrapped.state()
        assert held is None
        assert all(y == 0 or (x, y - 1) in cells for x, y in cells)


def test_the_vector_env_takes_the_view():
    vec = blockstack.vector.StackVectorEnv(4, blocks=3, view="side", backend="grid")
    _, infos = vec.reset(seed=1)
    assert infos["action_mask"][:, :5].sum() == 0, "nothing held: picks only"
    one = gym.make(ENV_ID, blocks=3, backend="grid")
    obs, _ = one.reset(seed=1)
    first, _ = vec.reset(seed=1)
    assert np.array_equal(first[0], obs)


def test_the_tabular_learner_trains_and_plays_the_side_view(tmp_path):
    # One goal of each shape by default; evaluated on two of the goals of two stacks.
    out = tmp_path / "side.safetensors"
    result = blockstack.train(
        view="side", backend="grid", eval_episodes=40, eval_goals="0,1/2:2/1,0", eval_epsilon=0.0, out=str(out)
    )
    assert result["view"] == "side"
    assert result["repr"] == "role-towers"
    assert result["goals"] == "0,1,2:0,1/2:0/1/2"
    assert result["eval_failures"] == 0
    assert result["eval_mean_ratio_to_optimum"] <= 1.05
    model = blockstack.load(str(out))
    assert model.world["view"] == "side"
    report = model.evaluate(episodes=20, goals="1,2/0:2/0/1", epsilon=0.0, backend="grid")
    assert report["failures"] == 0
    assert report["mean_ratio_to_optimum"] <= 1.05


def test_the_state_observation_keeps_the_goals_towers_apart():
    # `0,1/2` and `0,1,2` list the same blocks; `goal_tower` tells them apart, and a goal
    # that leaves a block free marks the entries past its blocks -1.
    for goal, blocks, order, towers in [
        ("0,1/2", 3, [0, 1, 2], [0, 0, 1]),
        ("0,1,2", 3, [0, 1, 2], [0, 0, 0]),
        ("1,3,2/", 4, [1, 3, 2, -1], [0, 0, 0, -1]),
    ]:
        env = gym.make(ENV_ID, blocks=blocks, goal=goal, obs="state", backend="grid")
        obs, info = env.reset(seed=2)
        assert obs["goal"].tolist() == order and obs["goal_tower"].tolist() == towers
        assert info["goal"].tolist() == order and info["goal_tower"].tolist() == towers
        assert env.observation_space.contains(obs)
        vec = blockstack.vector.StackVectorEnv(2, blocks=blocks, goal=goal, obs="state", view="side", backend="grid")
        batch, infos = vec.reset(seed=2)
        assert batch["goal_tower"].tolist() == [towers, towers]
        assert infos["goal_tower"].tolist() == [towers, towers]
        demos = blockstack.demonstrations(1, blocks=blocks, goal=goal, obs="state", view="side", backend="grid")
        assert demos["observations"]["goal_tower"][0].tolist() == towers
