"""``blockstack.load`` of a relational policy (``blockstack dqn --preset general``): it plays
the side view a block move at a time, in an environment of block moves."""

import numpy as np
import pytest

import blockstack


@pytest.fixture(scope="module")
def general(tmp_path_factory, cli):
    path = tmp_path_factory.mktemp("general") / "general.safetensors"
    cli("dqn", "--preset", "general", "--blocks", "6", "--steps", "20", "--batch", "16", "--seed", "2", "--out", path)
    return path


def test_a_relational_policy_plays_legal_block_moves(general):
    model = blockstack.load(general)
    assert model.kind == "relational" and model.world["view"] == "side"
    env = model.make_env(blocks=5, backend="grid")
    for seed in range(3):
        obs, info = env.reset(seed=seed)
        model.reset(seed)
        for _ in range(4 * 5):
            move, state = model.predict(obs)
            assert state is None and info["action_mask"][move] == 1, "a legal block move"
            assert model.predict(obs) == (move, None), "greedy: the same move again"
            obs, _, terminated, truncated, info = env.step(move)
            if terminated or truncated:
                break


def test_a_relational_policy_is_not_played_by_gripper_actions(general):
    model = blockstack.load(general)
    env = model.make_env(actions="gripper", backend="grid")
    obs, _ = env.reset(seed=1)
    with pytest.raises(ValueError, match="block moves"):
        model._native.act([tuple(int(v) for v in c) for c in np.asarray(obs["blocks"])], None,
                          [int(b) for b in obs["goal"]], [int(t) for t in obs["goal_tower"]])


def test_train_dqn_general_writes_the_clis_bytes(general, tmp_path):
    """``general`` is one of the library's presets: Python's trainer resolves it as the CLI
    does, so the same settings give the same file."""
    out = tmp_path / "python.safetensors"
    result = blockstack.train_dqn(preset="general", blocks=6, steps=20, batch=16, seed=2, out=str(out))
    assert out.read_bytes() == general.read_bytes()
    assert result["blocks"] == 6 and result["seed"] == 2 and result["describe"].startswith("relational")
    assert blockstack.load(out).kind == "relational"


@pytest.mark.parametrize(
    "settings, words",
    [
        ({"gamma": 0.9}, "gamma does not apply to the general preset"),
        ({"view": "top"}, "view does not apply to the general preset"),
        ({"blocks": 65}, "choose 2 to 64"),
        ({"checkpoint": "ck"}, "checkpoint is a network run's"),
    ],
)
def test_train_dqn_general_refuses_what_it_does_not_take(settings, words, tmp_path):
    if "checkpoint" in settings:
        settings = {"checkpoint": str(tmp_path / settings["checkpoint"])}
    with pytest.raises(ValueError, match=words):
        blockstack.train_dqn(preset="general", steps=1, out=str(tmp_path / "never.safetensors"), **settings)
    assert not (tmp_path / "never.safetensors").exists()
