"""The Gymnasium environment: the env checker, seeding, the CLI's trajectories, masks,
planners and bad input."""

import json
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import blockstack

ENV_ID = "blockstack/Stack-v0"


@pytest.mark.parametrize("backend", ["physics", "grid"])
@pytest.mark.parametrize("obs", ["planes", "role-planes", "frame", "paper-screen", "state"])
@pytest.mark.parametrize("render_mode", ["rgb_array", "ansi"])
def test_env_checker_passes_without_a_warning(obs, backend, render_mode):
    env = gym.make(ENV_ID, obs=obs, backend=backend, render_mode=render_mode, disable_env_checker=True)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(env.unwrapped, skip_render_check=False)
        env.reset(seed=3)
        for _ in range(20):
            obs_, *_ = env.step(env.action_space.sample())
            assert env.observation_space.contains(obs_)


def trajectory(env, seed, actions):
    out = [env.reset(seed=seed)]
    for a in actions:
        out.append(env.step(a))
    return out


def same(a, b):
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if isinstance(a, (tuple, list)):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b))
    if isinstance(a, np.ndarray):
        return a.dtype == b.dtype and np.array_equal(a, b)
    return a == b


@pytest.mark.parametrize("obs", ["planes", "role-planes", "frame", "paper-screen", "state"])
def test_the_same_seed_gives_the_same_trajectory(obs):
    actions = np.random.default_rng(0).integers(0, 8, size=200)
    first = trajectory(gym.make(ENV_ID, obs=obs), 11, actions)
    again = trajectory(gym.make(ENV_ID, obs=obs), 11, actions)
    assert same(first, again)
    other = trajectory(gym.make(ENV_ID, obs=obs), 12, actions)
    assert not same(first[0], other[0])


def test_reset_without_a_seed_continues_the_generator():
    env = blockstack.StackEnv()
    env.reset(seed=5)
    a = env.reset()[0]
    env.reset(seed=5)
    assert np.array_equal(env.reset()[0], a)


def test_python_equals_the_clis_trajectory_step_for_step(cli, tmp_path):
    path = tmp_path / "t.jsonl"
    cli("run", "--agent", "random", "--goal", "1,0,2", "--episodes", "3", "--seed", "7",
        "--horizon", "60", "--backend", "physics", "--trajectory", path)
    lines = [json.loads(line) for line in path.read_text().splitlines()]
    env = gym.make(ENV_ID, goal="1,0,2", obs="state", horizon=60)
    steps = 0
    for line in lines:
        if line["type"] == "episode":
            obs, _ = env.reset(seed=line["seed"])
            assert obs["blocks"].tolist() == line["start"]
            assert obs["goal"].tolist() == line["goal"]
            continue
        obs, reward, terminated, truncated, _ = env.step(line["action"])
        steps += 1
        assert obs["blocks"].tolist() == line["blocks"]
        assert obs["held"] == (-1 if line["held"] is None else line["held"])
        assert (reward, terminated, truncated) == (line["reward"], line["terminated"], line["truncated"])
    assert steps >= 60


def test_episode_seeds_are_the_clis():
    # blockstack run --seed 7 resets its episode k with episode_seed(7, k).
    assert blockstack.episode_seed(7, 0) == 13309476754707697221


def test_info_reports_the_mask_blocked_moves_and_pairs():
    env = blockstack.StackEnv(goal="0,1", blocks=2, obs="state")
    obs, info = env.reset(options={"cells": [(0, 0), (2, 0)]})
    assert info["action_mask"].dtype == np.int8
    assert info["action_mask"].tolist() == [1] * 7  # every action is legal in the spec world
    assert env.action_masks().all()
    assert info["pairs_in_place"] == 0 and info["goal"].tolist() == [0, 1]
    _, _, _, _, info = env.step(6)  # pick 1
    _, _, _, _, info = env.step(1)  # down: the floor stops it
    assert info["blocked"]
    for a in (0, 2, 2):  # up, left, left: onto block 0
        obs, reward, terminated, _, info = env.step(a)
    assert terminated and reward == 10.0 and info["pairs_in_place"] == 1
    assert obs["blocks"].tolist() == [[0, 0], [0, 1]] and obs["held"] == 1


def test_planners_give_shortest_plans():
    env = blockstack.StackEnv(goal="1,0,2")
    for seed in range(5):
        env.reset(seed=seed)
        cells, held, goal = env.state()
        optimum = env.unwrapped.optimal_steps() if hasattr(env, "unwrapped") else env.optimal_steps()
        plan = blockstack.solve(cells, goal, held)
        assert len(plan) == optimum
        oracle = blockstack.solve(cells, "1,0,2", held, solver="oracle")
        assert len(oracle) >= optimum
        # Following the expert reaches the goal in exactly the optimum.
        for step in range(optimum):
            _, _, terminated, _, _ = env.step(env.expert_action())
            assert terminated == (step == optimum - 1)


def test_solve_reads_held_blocks_and_gives_nothing_when_the_goal_holds():
    assert blockstack.solve([(0, 0), (0, 1)], "0,1") == []
    plan = blockstack.solve([(0, 0), (3, 0)], [0, 1], held=1)
    assert len(plan) == 4  # left x3 then up: block 1 is held already


def test_solve_takes_the_protocol_as_the_cli_does(cli):
    cells, goal = [(0, 0), (3, 0), (5, 2)], "1,0,2"
    for protocol in ["free", "paper"]:
        plan = blockstack.solve(cells, goal, protocol=protocol)
        printed = cli("solve", "--start", "0,0;3,0;5,2", "--goal", goal, "--protocol", protocol, "--json")
        assert plan == json.loads(printed)["actions"]
    with pytest.raises(ValueError, match="choose one of free, paper"):
        blockstack.solve(cells, goal, protocol="strict")


def test_solve_plans_block_moves_in_the_side_view():
    # 1 on 0, 2 on 1; 3 alone. Goal: 1 on the table, 3 on 1, 2 on 3: four moves at least.
    cells = [(0, 0), (0, 1), (0, 2), (1, 0)]
    exact = blockstack.solve(cells, "1,3,2/", view="side")
    assert exact == [
        {"block": 2, "onto": "table"},
        {"block": 1, "onto": "table"},
        {"block": 3, "onto": 1},
        {"block": 2, "onto": 3},
    ]
    near = blockstack.solve(cells, "1,3,2/", view="side", solver="near-optimal")
    assert len(near) <= 2 * len(exact)
    assert blockstack.solve(cells, "0,1/3,2", view="side") == [{"block": 2, "onto": 3}]
    with pytest.raises(ValueError, match="floats"):
        blockstack.solve([(0, 0), (0, 2)], "0,1", view="side")
    # The side view's oracle is the near-optimal planner.
    assert blockstack.solve(cells, "1,3,2/", view="side", solver="oracle") == near
    with pytest.raises(ValueError, match="choose one of exact, exact-moves, near-optimal, optimal, oracle"):
        blockstack.solve(cells, "1,3,2/", view="side", solver="greedy")


def test_solve_counts_gripper_steps_in_the_side_view_as_the_cli_does(cli):
    cells, goal = [(0, 0), (0, 1), (0, 2), (1, 0)], "1,3,2/"
    start = ";".join(f"{x},{y}" for x, y in cells)
    plans = {}
    for solver in ["exact", "near-optimal", "oracle"]:
        plan = blockstack.solve(cells, goal, view="side", cost="steps", solver=solver)
        printed = json.loads(
            cli("solve", "--view", "side", "--start", start, "--goal", goal, "--cost", "steps",
                "--solver", solver, "--json")
        )
        assert plan == printed["actions"] and printed["length"] == len(plan)
        plans[solver] = plan
    assert plans["oracle"] == plans["near-optimal"]
    assert len(plans["exact"]) <= len(plans["near-optimal"])
    # Four block moves at the fewest, each at least Pick, a move and Drop.
    assert len(plans["exact"]) >= 3 * 4
    # Block moves as before; from a held block, the exact count as the CLI gives it.
    assert blockstack.solve(cells, goal, view="side", cost="moves") == blockstack.solve(cells, goal, view="side")
    held_cells = [(0, 0), (0, 1), (0, 2), (1, 3)]
    held = blockstack.solve(held_cells, goal, held=3, view="side", cost="steps")
    printed = json.loads(
        cli("solve", "--view", "side", "--start", "0,0;0,1;0,2;1,3", "--held", 3, "--goal", goal,
            "--cost", "steps", "--json")
    )
    assert held == printed["actions"] and held[-1] == 4  # the last action lets go: Drop
    with pytest.raises(ValueError, match="choose steps or moves"):
        blockstack.solve(cells, goal, view="side", cost="seconds")
    with pytest.raises(ValueError, match='pass view="side"'):
        blockstack.solve(cells, "0,1,2,3", cost="moves")


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"reward": "shiny"}, "cannot read reward"),
        ({"goal": "0,0,1"}, "is not a permutation"),
        ({"goal": "0,1"}, "goal"),
        ({"backend": "lego"}, "choose physics or grid"),
        ({"obs": "smell"}, "choose one of planes, role-planes, frame, paper-screen, screen, state"),
        ({"obs": "pixels"}, "frame .*paper-screen"),
        ({"blocks": 1}, "1 blocks is not allowed"),
        ({"grid": (2, 2), "blocks": 3}, "taller than the grid"),
        ({"grid": (0, 5)}, "grid 0x5 is not allowed"),
        ({"profile": "nonsense"}, "profile"),
    ],
)
def test_bad_config_is_a_value_error_with_the_rust_message(kwargs, message):
    with pytest.raises(ValueError, match=message):
        gym.make(ENV_ID, **kwargs)


@pytest.mark.parametrize(
    "action, message",
    [
        (8, "action 8 is out of range: with 3 blocks the actions are 0..8"),
        (-1, "action -1 is out of range"),
        (1.0, "an action is one integer"),
        (np.float32(2), "an action is one integer"),
        (np.array([1, 2]), "shape"),
        ("up", "an action is one integer"),
        (True, "an action is one integer"),
    ],
)
def test_bad_actions_are_value_errors_and_the_env_lives_on(action, message):
    env = blockstack.StackEnv()
    env.reset(seed=1)
    with pytest.raises(ValueError, match=message):
        env.step(action)
    env.step(np.int64(5))
    env.step(np.array(4))


def test_stepping_before_reset_or_after_the_end_is_a_value_error():
    env = blockstack.StackEnv(max_episode_steps=1)
    with pytest.raises(ValueError, match="has not been reset"):
        env.step(0)
    env.reset(seed=0)
    assert env.step(0)[3]
    with pytest.raises(ValueError, match="the episode has ended"):
        env.step(0)


def test_render_modes():
    env = blockstack.StackEnv(render_mode="rgb_array", goal="1,0,2")
    obs, _ = env.reset(seed=2)
    frame = env.render()
    assert frame.dtype == np.uint8 and frame.ndim == 3 and frame.shape[2] == 3
    text = blockstack.StackEnv(render_mode="ansi")
    text.reset(seed=2)
    assert "goal" in text.render() and "held: none" in text.render()
    pixels = blockstack.StackEnv(obs="frame", goal="1,0,2")
    assert np.array_equal(pixels.reset(seed=2)[0], frame)


def test_bad_seeds_are_value_errors():
    env = blockstack.StackEnv()
    for seed in (-1, 1.5, 2**64):
        with pytest.raises(ValueError, match="seed"):
            env.reset(seed=seed)


@pytest.mark.parametrize("profile", ["spec", "original"])
@pytest.mark.parametrize("backend", ["physics", "grid"])
def test_the_action_mask_is_the_set_of_actions_the_rust_rules_accept(profile, backend):
    env = blockstack.StackEnv(profile=profile, backend=backend, obs="state", goal="0,1,2")
    probe = blockstack.StackEnv(profile=profile, backend=backend, obs="state", goal="0,1,2", strict=True)
    lenient = blockstack.StackEnv(profile=profile, backend=backend, obs="state", goal="0,1,2")
    rng = np.random.default_rng(5)
    _, info = env.reset(seed=8)
    for _ in range(60):
        cells, held, goal = env.state()
        for action in range(env.action_space.n):
            probe.reset(options={"cells": cells, "held": held, "goal": goal})
            try:
                probe.step(action)
                accepted = True
            except ValueError as e:
                assert "not legal" in str(e) or "illegal" in str(e), e
                accepted = False
            assert accepted == bool(info["action_mask"][action]), (cells, held, action)
            # Without strict the same action is taken, as illegal exactly when refused.
            lenient.reset(options={"cells": cells, "held": held, "goal": goal})
            assert lenient.step(action)[4]["illegal"] == (not accepted), (cells, held, action)
        _, _, terminated, truncated, info = env.step(int(rng.choice(np.flatnonzero(info["action_mask"]))))
        if terminated or truncated:
            _, info = env.reset()


def test_the_original_profile_masks_by_the_papers_protocol():
    env = blockstack.StackEnv(profile="original", obs="state", goal="0,1,2")
    obs, info = env.reset(seed=3)
    # Nothing held: only the picks.
    assert info["action_mask"].tolist() == [0, 0, 0, 0, 0, 1, 1, 1]
    _, _, _, _, info = env.step(5)
    # Holding: the moves and drop only.
    assert info["action_mask"].tolist() == [1, 1, 1, 1, 1, 0, 0, 0]
    # A pick while holding changes nothing and says so; strict=True refuses it instead.
    before = env.state()
    _, reward, _, _, info = env.step(6)
    assert info["illegal"] and env.state() == before and reward == pytest.approx(-0.1)
    strict = blockstack.StackEnv(profile="original", obs="state", goal="0,1,2", strict=True)
    strict.reset(seed=3)
    strict.step(5)
    with pytest.raises(ValueError) as e:
        strict.step(6)
    assert "paper" in str(e.value)
