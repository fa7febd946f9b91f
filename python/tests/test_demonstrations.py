"""Expert demonstrations as arrays, and the CLI's recordings read into the same arrays."""

import numpy as np
import pytest

import blockstack

KEYS = ["observations", "next_observations", "actions", "rewards", "terminations", "truncations",
        "episode_starts", "episodes", "action_masks"]


def assert_same(a, b):
    assert a.keys() == b.keys()
    for k in a:
        if isinstance(a[k], dict):
            assert_same(a[k], b[k])
        else:
            assert a[k].dtype == b[k].dtype and np.array_equal(a[k], b[k]), k


def test_expert_episodes_are_shortest_plans():
    d = blockstack.demonstrations(8, expert="exact", blocks=3, seed=4, obs="state")
    assert sorted(d) == sorted(KEYS)
    starts = np.flatnonzero(d["episode_starts"])
    assert len(starts) == 8 and starts[0] == 0
    ends = np.flatnonzero(d["terminations"])
    assert len(ends) == 8 and not d["truncations"].any()
    assert d["actions"].dtype == np.int64 and d["rewards"].dtype == np.float64
    assert d["action_masks"].shape == (len(d["actions"]), 8) and d["action_masks"].dtype == np.int8
    obs = d["observations"]
    for start, end in zip(starts, ends):
        cells = [tuple(c) for c in obs["blocks"][start]]
        plan = blockstack.solve(cells, obs["goal"][start].tolist())
        assert end - start + 1 == len(plan)
        # Within an episode each next observation is the following observation.
        assert np.array_equal(d["next_observations"]["blocks"][start:end], obs["blocks"][start + 1:end + 1])
    assert (d["rewards"][ends] == 10.0).all()


def test_the_oracle_and_planes_work_too():
    d = blockstack.demonstrations(3, expert="oracle", blocks=2, seed=1, goal=[1, 0])
    t = len(d["actions"])
    assert d["observations"].shape == (t, 7, 7, 3) and d["observations"].dtype == np.uint8
    assert d["terminations"].sum() == 3


def test_demonstrations_equal_the_clis_exact_run_read_back(cli, tmp_path):
    path = tmp_path / "exact.jsonl"
    cli("run", "--agent", "exact", "--goal", "1,0,2", "--episodes", "5", "--seed", "7", "--trajectory", path)
    for obs in ("planes", "state"):
        ours = blockstack.demonstrations(5, expert="exact", seed=7, goal="1,0,2", obs=obs)
        assert_same(blockstack.read_recording(path, obs=obs), ours)


def test_a_demonstration_recording_reads_back_and_replays(cli, tmp_path):
    model, record = tmp_path / "m.json", tmp_path / "demos.jsonl"
    cli("train", "--games", "20", "--goals", "0,1,2", "--out", model)
    cli("correct", "--model", model, "--demonstrator", "1", "--demos", "2", "--goals", "0,1,2",
        "--seed", "3", "--out", tmp_path / "c.json", "--record", record)
    d = blockstack.read_recording(record, obs="state")
    starts = np.flatnonzero(d["episode_starts"])
    assert len(starts) == 2
    env = blockstack.StackEnv(goal="0,1,2", obs="state")
    for t, action in enumerate(d["actions"]):
        if d["episode_starts"][t]:
            env.reset(options={"cells": [tuple(c) for c in d["observations"]["blocks"][t]],
                               "held": None if d["observations"]["held"][t] < 0 else int(d["observations"]["held"][t])})
        obs, reward, terminated, truncated, _ = env.step(int(action))
        assert np.array_equal(obs["blocks"], d["next_observations"]["blocks"][t])
        assert obs["held"] == d["next_observations"]["held"][t]
        assert (terminated, truncated) == (d["terminations"][t], d["truncations"][t])


def test_bad_recordings_and_arguments_are_value_errors(tmp_path):
    bad = tmp_path / "bad.jsonl"
    bad.write_text('{"type":"episode","episode":0,"seed":1,"grid":[7,7],"goal":[0,1],"horizon":9,"start":[[0,0],[1,0]]}\nnot json\n')
    with pytest.raises(ValueError, match="line 2"):
        blockstack.read_recording(bad)
    with pytest.raises(ValueError, match="cannot read"):
        blockstack.read_recording(tmp_path / "missing.jsonl")
    with pytest.raises(ValueError, match="choose one of exact, exact-moves, near-optimal, optimal, oracle"):
        blockstack.demonstrations(1, expert="human")


def test_demonstrations_can_show_the_papers_screen_and_role_planes():
    screen = blockstack.demonstrations(2, expert="exact", seed=3, goal="1,0,2", obs="paper-screen")
    t = len(screen["actions"])
    assert screen["observations"].shape == (t, 100, 100, 3) and screen["observations"].dtype == np.uint8
    roles = blockstack.demonstrations(2, expert="exact", seed=3, goal="1,0,2", obs="role-planes")
    planes = blockstack.demonstrations(2, expert="exact", seed=3, goal="1,0,2", obs="planes")
    # Role planes are the block planes reordered by goal place: place 0 is block 1.
    order = [1, 0, 2, 3]
    assert np.array_equal(roles["observations"], planes["observations"][..., order])
