"""``blockstack.load``: a model trained with the CLI, loaded in Python, plays and evaluates
as the CLI plays and evaluates it."""

import json
import os

import numpy as np
import pytest

import blockstack


@pytest.fixture(scope="module")
def role_model(tmp_path_factory, cli):
    path = tmp_path_factory.mktemp("model") / "role.safetensors"
    cli("train", "--repr", "role", "--goals", "0,1,2", "--games", "400", "--backend", "grid", "--out", path)
    return path


@pytest.fixture(scope="module")
def network(tmp_path_factory, cli):
    path = tmp_path_factory.mktemp("network") / "net.safetensors"
    cli("dqn", "--preset", "dqn-planes", "--blocks", "2", "--steps", "60", "--seed", "3", "--out", path)
    return path


def cli_actions(cli, tmp_path, model, agent, goal, episodes, seed, extra=()):
    """The actions of each episode of ``blockstack run``, from its trajectory file."""
    trajectory = tmp_path / f"{agent}.jsonl"
    cli("run", "--agent", agent, "--model", model, "--goal", goal, "--episodes", episodes, "--seed", seed,
        "--epsilon", "0", "--trajectory", trajectory, *extra)
    actions = [[] for _ in range(episodes)]
    for line in trajectory.read_text().splitlines():
        record = json.loads(line)
        if record["type"] == "step":
            actions[record["episode"]].append(record["action"])
    return actions


def python_actions(model, goal, episodes, seed, **overrides):
    """The same episodes played from Python: reset with the CLI's episode seeds."""
    env = model.make_env(goal=goal, **overrides)
    out = []
    for k in range(episodes):
        s = blockstack.episode_seed(seed, k)
        obs, info = env.reset(seed=s)
        model.reset(s)
        actions, done = [], False
        while not done:
            action, state = model.predict(obs, deterministic=True)
            assert state is None
            actions.append(action)
            obs, reward, terminated, truncated, info = env.step(action)
            done = terminated or truncated
        out.append(actions)
    return out


def test_a_tabular_model_plays_the_clis_greedy_trajectory(cli, tmp_path, role_model):
    model = blockstack.load(role_model)
    assert model.kind == "q" and model.world["blocks"] == 3
    expected = cli_actions(cli, tmp_path, role_model, "q", "1,0,2", 3, 7, ("--backend", "physics"))
    assert python_actions(model, "1,0,2", 3, 7) == expected


def test_a_side_view_model_plays_the_clis_greedy_trajectory_on_a_goal_of_towers(cli, tmp_path):
    # `predict` reads the goal's towers from the state observation: on `0,1/2` (not `0,1,2`)
    # it plays what `blockstack run` plays.
    path = tmp_path / "side.safetensors"
    cli("train", "--view", "side", "--backend", "grid", "--games", "20000", "--out", path)
    model = blockstack.load(path)
    expected = cli_actions(cli, tmp_path, path, "q", "0,1/2", 10, 4, ("--backend", "grid"))
    assert python_actions(model, "0,1/2", 10, 4, backend="grid") == expected
    obs, _ = model.make_env(goal="0,1/2", backend="grid").reset(seed=1)
    with pytest.raises(ValueError, match="goal_tower"):
        model.predict({**obs, "goal_tower": obs["goal_tower"][:2]})


@pytest.fixture(scope="module")
def pixel_network(tmp_path_factory, cli):
    # Without the no-op mask, which a picture cannot give, so that the network plays the
    # same actions on its picture as on the state.
    path = tmp_path_factory.mktemp("pixels") / "pixels.safetensors"
    cli("dqn", "--preset", "dqfd-screen", "--blocks", "2", "--demos", "exact:10", "--pretrain", "30", "--steps", "60",
        "--hidden", "16", "--mask-noops", "false", "--seed", "3", "--out", path)
    return path


def test_a_pixel_network_plays_on_its_picture_what_it_plays_on_the_state(cli, tmp_path, pixel_network):
    model = blockstack.load(pixel_network)
    assert model.picture == "screen"
    expected = cli_actions(cli, tmp_path, pixel_network, "dqn", "1,0", 2, 5, ("--blocks", "2", "--horizon", "40"))
    assert python_actions(model, "1,0", 2, 5, horizon=40) == expected
    env = model.make_env(goal="1,0", obs=model.picture, horizon=40)
    for k in range(2):
        obs, info = env.reset(seed=blockstack.episode_seed(5, k))
        assert obs.shape == (28, 28, 3) and obs.dtype == np.uint8
        actions, done = [], False
        while not done:
            action, _ = model.predict(obs, info=info)
            actions.append(action)
            obs, _, terminated, truncated, info = env.step(action)
            done = terminated or truncated
        assert actions == expected[k]
    with pytest.raises(ValueError, match="info"):
        model.predict(obs)
    with pytest.raises(ValueError, match="values"):
        model.predict(obs[:-1], info=info)


def test_the_pixels_network_on_the_papers_screen_plays_on_it(tmp_path):
    # Trained by Python's trainer with screen="paper": it reads the environment's
    # paper-screen observation, and plays on it what it plays on the state.
    path = tmp_path / "paper.safetensors"
    blockstack.train_dqn(preset="dqfd-screen", blocks=2, screen="paper", demos="exact:10", pretrain=20, steps=30,
                         hidden=16, mask_noops=False, seed=3, out=str(path))
    model = blockstack.load(path)
    assert model.picture == "paper-screen"
    env, state_env = (model.make_env(goal="0,1", obs=obs, horizon=30) for obs in ("paper-screen", "state"))
    for seed in range(3):
        (obs, info), (state, _) = env.reset(seed=seed), state_env.reset(seed=seed)
        assert obs.shape == (100, 100, 3) and obs.dtype == np.uint8
        done = False
        while not done:
            action, _ = model.predict(obs, info=info)
            assert action == model.predict(state)[0]
            obs, _, terminated, truncated, info = env.step(action)
            state, *_ = state_env.step(action)
            done = terminated or truncated


def test_a_network_on_planes_refuses_a_picture(network):
    model = blockstack.load(network)
    assert model.picture is None
    obs, info = model.make_env(obs="role-planes").reset(seed=1)
    with pytest.raises(ValueError, match="obs='state'"):
        model.predict(obs, info=info)


def test_a_network_plays_the_clis_greedy_trajectory(cli, tmp_path, network):
    model = blockstack.load(network)
    assert model.kind == "dqn" and model.world["blocks"] == 2
    expected = cli_actions(cli, tmp_path, network, "dqn", "1,0", 2, 5, ("--blocks", "2", "--horizon", "40"))
    assert python_actions(model, "1,0", 2, 5, horizon=40) == expected


@pytest.mark.parametrize("fixture", ["role_model", "network"])
def test_evaluate_is_what_eval_json_prints(cli, fixture, request):
    path = request.getfixturevalue(fixture)
    model = blockstack.load(path)
    ours = model.evaluate(episodes=4, seed=3, epsilon=0.0, backend="grid")
    theirs = json.loads(cli("eval", "--model", path, "--episodes", 4, "--seed", 3, "--epsilon", 0,
                            "--backend", "grid", "--json"))
    assert ours == theirs


def test_files_that_are_not_models_are_value_errors(tmp_path):
    bad = tmp_path / "bad.safetensors"
    bad.write_bytes(b"not a model")
    with pytest.raises(ValueError, match="bad.safetensors"):
        blockstack.load(bad)
    with pytest.raises(ValueError):
        blockstack.load(tmp_path / "missing.safetensors")


def test_predict_reads_the_state_observation(role_model):
    model = blockstack.load(role_model)
    env = model.make_env(obs="planes")
    obs, _ = env.reset(seed=1)
    with pytest.raises(ValueError, match="obs='state'"):
        model.predict(obs)


def test_a_model_refuses_an_environment_of_another_world(role_model, tmp_path):
    """``make_env`` with a grid, block count or view the model never learnt is refused, as
    ``blockstack run --model`` refuses it, instead of playing a world it does not know."""
    model = blockstack.load(role_model)
    for overrides, says in [
        ({"grid": (5, 5)}, "the agent plays 3 blocks on a 7x7 grid, the world has 3 blocks on a 5x5 grid"),
        ({"blocks": 2, "goal": "1,0"}, "the world has 2 blocks"),
        ({"view": "side"}, "the model learnt the top view; it cannot play the side view"),
    ]:
        with pytest.raises(ValueError, match=says):
            model.make_env(**overrides)
    side = tmp_path / "side.safetensors"
    blockstack.train(view="side", backend="grid", games=5, out=str(side))
    with pytest.raises(ValueError, match="the model learnt the side view; it cannot play the top view"):
        blockstack.load(side).make_env(view="top")


def test_predict_refuses_fractions_instead_of_rounding_them(role_model):
    model = blockstack.load(role_model)
    obs, _ = model.make_env(backend="grid").reset(seed=1)
    model.predict({k: np.asarray(v, dtype=float) for k, v in obs.items()})  # whole numbers as floats: read
    bad = dict(obs, blocks=obs["blocks"] + 0.5)
    with pytest.raises(ValueError, match="observation\\['blocks'\\] holds whole numbers"):
        model.predict(bad)
    with pytest.raises(ValueError, match="observation\\['held'\\]"):
        model.predict(dict(obs, held=True))


def test_a_fifo_is_refused_at_once_not_waited_on(tmp_path):
    """A pipe with no writer would block ``open`` forever (and ignore Ctrl-C): it is
    refused before it is opened, as the CLI refuses it."""
    import subprocess
    import sys

    fifo = tmp_path / "model.safetensors"
    os.mkfifo(fifo)
    script = (
        "import blockstack, sys\n"
        "try:\n"
        f"    blockstack.load({str(fifo)!r})\n"
        "except ValueError as e:\n"
        "    print(e)\n"
    )
    run = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stderr
    assert "a pipe or a device is not supported as a model file" in run.stdout, run.stdout
