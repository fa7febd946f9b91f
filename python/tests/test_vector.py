"""StackVectorEnv: the same as Gymnasium's SyncVectorEnv of the same environments, step
for step, autoresets included; bad actions are ValueErrors."""

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode, SyncVectorEnv

import blockstack
from blockstack.vector import StackVectorEnv

ENV_ID = "blockstack/Stack-v0"


def assert_same(a, b, where):
    if isinstance(a, tuple):
        assert isinstance(b, tuple) and len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b)):
            assert_same(x, y, f"{where}[{i}]")
    elif isinstance(a, dict):
        assert a.keys() == b.keys(), where
        for k in a:
            assert_same(a[k], b[k], f"{where}.{k}")
    elif isinstance(a, np.ndarray) and a.dtype == object:
        assert b.dtype == object and a.shape == b.shape, where
        for i, (x, y) in enumerate(zip(a, b)):
            if x is None or y is None:
                assert x is None and y is None, f"{where}[{i}]"
            else:
                assert_same(x, y, f"{where}[{i}]")
    else:
        a, b = np.asarray(a), np.asarray(b)
        assert a.dtype == b.dtype, f"{where}: {a.dtype} != {b.dtype}"
        assert np.array_equal(a, b), where


def actions_for(sync, masks, rng, expert_share):
    """Mostly expert actions (so episodes reach the goal), some random ones; legal ones."""
    out = []
    for env, mask in zip(sync.envs, masks):
        try:
            if rng.random() < expert_share:
                a = env.unwrapped.expert_action()
                if mask[a]:
                    out.append(a)
                    continue
        except ValueError:  # the goal holds: this env resets on its next step
            pass
        out.append(int(rng.choice(np.flatnonzero(mask))))
    return np.array(out)


@pytest.mark.parametrize("mode", [AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP])
@pytest.mark.parametrize(
    "kwargs",
    [
        {"obs": "planes", "backend": "physics", "blocks": 2, "horizon": 9},
        {"obs": "state", "backend": "grid", "blocks": 3, "reward": "dense", "horizon": 12},
        {"obs": "frame", "backend": "physics", "blocks": 2, "goal": "1,0", "horizon": 6},
        {"obs": "paper-screen", "backend": "grid", "blocks": 2, "goal": "1,0", "horizon": 6},
        {"obs": "role-planes", "backend": "grid", "blocks": 3, "goal": "2,0,1", "horizon": 6},
        {"obs": "planes", "backend": "grid", "blocks": 2, "profile": "original", "horizon": 10},
    ],
)
def test_stack_vector_env_equals_sync_vector_env(mode, kwargs):
    n = 6
    sync = SyncVectorEnv([lambda: gym.make(ENV_ID, **kwargs) for _ in range(n)], autoreset_mode=mode)
    ours = StackVectorEnv(n, autoreset_mode=mode, **kwargs)
    assert ours.metadata["autoreset_mode"] == mode
    assert ours.single_observation_space == sync.single_observation_space
    assert ours.observation_space == sync.observation_space
    assert ours.action_space == sync.action_space
    expected = sync.reset(seed=21)
    assert_same(ours.reset(seed=21), expected, "reset")
    rng = np.random.default_rng(1)
    ends = 0
    for t in range(40):
        actions = actions_for(sync, expected[-1]["action_mask"], rng, expert_share=0.8)
        expected = sync.step(actions)
        got = ours.step(actions)
        assert_same(got, expected, f"step {t}")
        ends += int(np.sum(expected[2] | expected[3]))
        if t == 20:
            expected = sync.reset()
            assert_same(ours.reset(), expected, "reset without a seed")
    assert ends > n, "episodes ended, both ways"


@pytest.mark.parametrize("mode", [AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP])
@pytest.mark.parametrize("obs", ["planes", "state"])
def test_threads_change_nothing(mode, obs):
    # Above PARALLEL_FROM_ENVS, and odd: two threads each write a chunk of unequal length.
    n = blockstack.vector.PARALLEL_FROM_ENVS + 3
    kwargs = {"obs": obs, "backend": "grid", "blocks": 3, "max_episode_steps": 25, "autoreset_mode": mode}
    one = StackVectorEnv(n, threads=1, **kwargs)
    two = StackVectorEnv(n, threads=2, **kwargs)
    assert_same(one.reset(seed=4), two.reset(seed=4), "reset")
    rng = np.random.default_rng(2)
    ends = 0
    for t in range(60):
        actions = rng.integers(0, 8, size=n)
        got = two.step(actions)
        assert_same(one.step(actions), got, f"step {t}")
        ends += int(np.sum(got[2] | got[3]))
    assert ends > n, "episodes ended in both chunks"


def test_make_vec_uses_the_native_vector_env():
    envs = gym.make_vec(ENV_ID, num_envs=4, vectorization_mode="vector_entry_point", blocks=2)
    assert isinstance(envs, StackVectorEnv)
    obs, info = envs.reset(seed=0)
    assert obs.shape == (4, 7, 7, 3) and info["action_mask"].shape == (4, 7)


def test_without_copies_the_buffers_are_returned():
    envs = StackVectorEnv(4, copy=False)
    obs, _ = envs.reset(seed=0)
    obs2, rewards, *_ = envs.step(np.zeros(4, dtype=np.int64))
    assert obs2 is obs


@pytest.mark.parametrize(
    "actions, message",
    [
        (np.array([0, 1, 2]), r"shape \(4,\)"),
        (np.array([0.0, 1.0, 2.0, 3.0]), "integer array"),
        (np.array([[0, 1], [2, 3]]), "integer array"),
        (np.array([0, 1, 2, 8]), "action 8 is out of range: with 3 blocks the actions are 0..8"),
        (np.array([0, -1, 2, 3]), "action -1 is out of range"),
        ([0, 1, 2, 3.5], "integer array"),
    ],
)
def test_bad_actions_are_value_errors_and_nothing_steps(actions, message):
    envs = StackVectorEnv(4, threads=2)
    obs, _ = envs.reset(seed=3)
    with pytest.raises(ValueError, match=message):
        envs.step(actions)
    # Nothing moved, and the batch steps on.
    again, _ = StackVectorEnv(4).reset(seed=3)
    assert np.array_equal(obs, again)
    envs.step(np.array([5, 6, 7, 4], dtype=np.uint8))


def test_stepping_before_reset_is_a_value_error():
    with pytest.raises(ValueError, match="has not been reset"):
        StackVectorEnv(2).step(np.zeros(2, dtype=np.int64))


def test_bad_vector_arguments_are_value_errors():
    with pytest.raises(ValueError, match="at least one environment"):
        StackVectorEnv(0)
    with pytest.raises(ValueError, match="cannot read reward"):
        StackVectorEnv(2, reward="shiny")
    with pytest.raises(ValueError, match="3 seeds given for 2"):
        StackVectorEnv(2).reset(seed=[1, 2, 3])
    with pytest.raises(ValueError, match="takes no options"):
        StackVectorEnv(2).reset(options={"reset_mask": np.ones(2, dtype=bool)})
