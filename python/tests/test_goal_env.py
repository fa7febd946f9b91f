"""``blockstack/StackGoal-v0``: the goal-conditioned environment HER runs on."""

import gymnasium as gym
import numpy as np
import pytest

import blockstack
from blockstack import StackGoalEnv


def test_observations_are_the_goal_env_dict_and_fit_the_space():
    env = gym.make("blockstack/StackGoal-v0", blocks=3)
    obs, info = env.reset(seed=3)
    assert set(obs) == {"observation", "achieved_goal", "desired_goal"}
    assert env.observation_space.contains(obs)
    assert obs["observation"].shape == (7, 7, 4)
    assert sorted(obs["desired_goal"].tolist()) == [0, 1, 2]
    np.testing.assert_array_equal(obs["desired_goal"], info["goal"])
    # The planes are StackEnv's, which do not depend on the goal.
    planes, _ = blockstack.StackEnv(blocks=3, obs="planes").reset(seed=3)
    np.testing.assert_array_equal(obs["observation"], planes)


@pytest.mark.parametrize("reward", ["sparse", "step-cost"])
def test_the_step_is_what_compute_reward_terminated_and_truncated_say(reward):
    env = gym.make("blockstack/StackGoal-v0", blocks=2, reward=reward, horizon=60, backend="grid")
    goal_env = env.unwrapped
    rng = np.random.default_rng(0)
    seen_success = False
    for episode in range(30):
        obs, info = env.reset(seed=episode)
        for _ in range(60):
            obs, r, terminated, truncated, info = env.step(int(rng.integers(0, 7)))
            args = (obs["achieved_goal"], obs["desired_goal"], info)
            assert r == goal_env.compute_reward(*args)
            assert terminated == goal_env.compute_terminated(*args)
            assert truncated == goal_env.compute_truncated(*args)
            assert info["is_success"] == terminated
            if terminated or truncated:
                seen_success |= terminated
                break
    assert seen_success, "random play on 2 blocks reaches some goals in 30 games"


def test_the_achieved_goal_is_the_stack_standing_and_relabelling_rewards_it():
    env = StackGoalEnv(blocks=3, backend="grid")
    # 0 on the floor, 2 on 0, 1 on 2: the stack 0,2,1 stands; the goal is 1,0,2.
    obs, _ = env.reset(options={"cells": [(3, 0), (3, 2), (3, 1)], "goal": "1,0,2"})
    assert obs["achieved_goal"].tolist() == [0, 2, 1]
    assert env.compute_reward(obs["achieved_goal"], obs["desired_goal"], {}) == 0.0
    # HER relabels the desired goal with an achieved one: the batch's rewards follow.
    achieved = np.array([[0, 2, 1], [0, 2, 1], [-1, -1, -1]])
    desired = np.array([[0, 2, 1], [1, 0, 2], [-1, -1, -1]])
    np.testing.assert_array_equal(env.compute_reward(achieved, desired, [{}] * 3), [10.0, 0.0, 0.0])
    # Two of three blocks stacked: no goal stands.
    obs, _ = env.reset(options={"cells": [(3, 0), (3, 1), (5, 5)], "goal": "0,1,2"})
    assert obs["achieved_goal"].tolist() == [-1, -1, -1]


def test_reaching_the_goal_ends_the_episode_with_the_worlds_reward():
    env = StackGoalEnv(blocks=2, backend="grid")
    env.reset(options={"cells": [(2, 0), (3, 1)], "goal": "0,1"})
    env.step(6)  # pick block 1
    obs, r, terminated, truncated, info = env.step(2)  # left: onto block 0
    assert (r, terminated, truncated, info["is_success"]) == (10.0, True, False, True)
    assert obs["achieved_goal"].tolist() == obs["desired_goal"].tolist() == [0, 1]


def test_rewards_that_are_not_a_function_of_the_goals_are_refused():
    for reward in ["dense", "paper", "paper-code"]:
        with pytest.raises(ValueError, match="sparse or step-cost"):
            StackGoalEnv(blocks=3, reward=reward)
    with pytest.raises(ValueError, match="shape"):
        StackGoalEnv(blocks=3).compute_reward(np.zeros(2), np.zeros(2), {})


def test_stable_baselines3_dqn_with_her_runs_unchanged():
    sb3 = pytest.importorskip("stable_baselines3", reason="stable-baselines3 (and torch) not installed")
    from stable_baselines3.common.env_checker import check_env

    env = gym.make("blockstack/StackGoal-v0", blocks=2, horizon=50, backend="grid")
    check_env(env.unwrapped)
    model = sb3.DQN(
        "MultiInputPolicy",
        env,
        replay_buffer_class=sb3.HerReplayBuffer,
        replay_buffer_kwargs=dict(n_sampled_goal=4, goal_selection_strategy="future"),
        learning_starts=100,
        batch_size=32,
        seed=0,
        device="cpu",
    )
    model.learn(total_timesteps=300)
    assert model.replay_buffer.size() == 300
    obs, _ = env.reset(seed=1)
    action, _ = model.predict(obs, deterministic=True)
    assert env.action_space.contains(int(action))


def test_a_goal_of_towers_is_refused_rather_than_relabelled_wrongly():
    """A goal of towers leaves blocks free, so the stack standing (the achieved goal) is not
    it: the environment would pay 10 where ``compute_reward`` gives 0. Refused, in one line."""
    for goal in ["0,1/2", "0,1/", "2/1/0"]:
        with pytest.raises(ValueError, match="not one tower of every block"):
            StackGoalEnv(blocks=3, goal=goal, view="side")


@pytest.mark.parametrize("view", ["top", "side"])
def test_the_env_and_compute_reward_agree_in_either_view(view):
    env = StackGoalEnv(blocks=2, view=view, backend="grid", horizon=60)
    rng = np.random.default_rng(1)
    reached = 0
    for episode in range(40):
        obs, info = env.reset(seed=episode)
        for _ in range(60):
            # A legal action: the side view has rules of its own (only a clear block is picked).
            action = int(rng.choice(np.flatnonzero(info["action_mask"])))
            obs, r, terminated, truncated, info = env.step(action)
            args = (obs["achieved_goal"], obs["desired_goal"], info)
            assert r == env.compute_reward(*args)
            assert terminated == env.compute_terminated(*args) == info["is_success"]
            if terminated or truncated:
                reached += terminated
                break
    assert reached > 0


def test_compute_reward_refuses_goals_that_are_not_block_ids():
    env = StackGoalEnv(blocks=3)
    goal = np.array([0, 1, 2])
    assert env.compute_reward(goal.astype(np.float32), goal, {}) == 10.0  # a buffer's floats
    for bad in [goal + 0.5, goal.astype(bool), np.array(["0", "1", "2"])]:
        with pytest.raises(ValueError, match="whole numbers"):
            env.compute_reward(bad, goal, {})
