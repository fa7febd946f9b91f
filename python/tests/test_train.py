"""``blockstack.train`` and ``blockstack train`` resolve settings with one library call, so
the same settings give the same model file, byte for byte."""

import pytest

import blockstack

# (CLI flags, Python keyword arguments): the same settings in each spelling.
SETTINGS = [
    # --repr role under spec takes the optimal preset (gamma 1, epsilon 0, replays).
    (["--repr", "role", "--goals", "0,1,2", "--games", "60"], dict(repr="role", goals="0,1,2", games=60)),
    # The paper's learner, explicit flags over it.
    (
        ["--blocks", "2", "--goals", "0,1:1,0", "--games", "40", "--gamma", "0.5", "--seed", "4"],
        dict(blocks=2, goals="0,1:1,0", games=40, gamma=0.5, seed=4),
    ),
    # The authors' world and learner, a schedule named, replays off.
    (
        ["--profile", "original", "--blocks", "2", "--goals", "0,1", "--games", "3", "--schedule", "spec"],
        dict(profile="original", blocks=2, goals="0,1", games=3, schedule="spec"),
    ),
    (
        ["--preset", "optimal", "--grid", "5x5", "--goals", "1,0,2", "--games", "30", "--final-replay=false"],
        dict(preset="optimal", grid=(5, 5), goals="1,0,2", games=30, final_replay=False),
    ),
]


@pytest.mark.parametrize("flags,kwargs", SETTINGS)
def test_python_and_the_cli_write_the_same_model_file(cli, tmp_path, flags, kwargs):
    by_cli, by_python = tmp_path / "cli.safetensors", tmp_path / "python.safetensors"
    cli("train", *flags, "--backend", "grid", "--out", by_cli)
    blockstack.train(**kwargs, backend="grid", out=str(by_python))
    assert by_cli.read_bytes() == by_python.read_bytes()


def test_the_optimal_preset_with_the_authors_schedule_is_refused_as_the_cli_refuses_it():
    with pytest.raises(ValueError, match="--schedule spec"):
        blockstack.train(preset="optimal", schedule="paper-code", goals="0,1,2", games=1)


def test_the_output_folder_is_checked_before_training(tmp_path):
    with pytest.raises(ValueError, match="cannot write"):
        blockstack.train(games=10**9, goals="0,1,2", out=str(tmp_path / "missing" / "m.safetensors"))


def test_a_grid_is_text_or_a_pair():
    a = blockstack.train(grid="5x5", goals="0,1,2", games=2, backend="grid")
    b = blockstack.train(grid=(5, 5), goals="0,1,2", games=2, backend="grid")
    assert a["grid"] == b["grid"] == "5x5"
    with pytest.raises(ValueError, match="grid"):
        blockstack.train(grid=[5, "x"], goals="0,1,2", games=2)


# The network trainer: (CLI flags of `blockstack dqn`, keyword arguments of `train_dqn`).
DQN_SETTINGS = [
    # DQfD on planes (the preset the demonstrations point to), a small network.
    (
        ["--blocks", "2", "--demos", "exact:40", "--pretrain", "60", "--steps", "120", "--hidden", "32", "--seed", "3"],
        dict(blocks=2, demos="exact:40", pretrain=60, steps=120, hidden=32, seed=3),
    ),
    # A named preset, its learning rate changed (the final rate follows), on the paper's screen.
    (
        ["--preset", "paper-dqfd", "--blocks", "2", "--demos", "exact:5", "--pretrain", "3", "--steps", "70",
         "--batch", "8", "--lr", "2e-4", "--goals", "1,0"],
        dict(preset="paper-dqfd", blocks=2, demos="exact:5", pretrain=3, steps=70, batch=8, lr=2e-4, goals="1,0"),
    ),
    # Hindsight relabelling, a 5x5 grid as a pair.
    (
        ["--preset", "her-planes", "--blocks", "2", "--grid", "5x5", "--steps", "150", "--hidden", "16",
         "--buffer", "500"],
        dict(preset="her-planes", blocks=2, grid=(5, 5), steps=150, hidden=16, buffer=500),
    ),
    # The conv network on the compact screen, the goal as a strip; the preset by its old name
    # in Python, its new one on the command line: the same preset.
    (
        ["--preset", "dqfd-screen", "--blocks", "2", "--demos", "exact:10", "--pretrain", "20", "--steps", "80",
         "--hidden", "16", "--screen", "strip"],
        dict(preset="pixels", blocks=2, demos="exact:10", pretrain=20, steps=80, hidden=16, screen="strip"),
    ),
]


@pytest.mark.parametrize("flags,kwargs", DQN_SETTINGS)
def test_python_and_the_cli_write_the_same_network_file(cli, tmp_path, flags, kwargs):
    by_cli, by_python = tmp_path / "cli.safetensors", tmp_path / "python.safetensors"
    cli("dqn", *flags, "--out", by_cli)
    result = blockstack.train_dqn(**kwargs, out=str(by_python))
    assert by_cli.read_bytes() == by_python.read_bytes()
    assert result["steps"] == kwargs["steps"] and result["games"] >= 1
    assert blockstack.load(str(by_python)).kind == "dqn"


def test_the_network_trainer_refuses_what_the_cli_refuses(tmp_path):
    for kwargs, says in [
        (dict(preset="best"), "unknown preset"),
        (dict(obs="role-planes", net="paper"), "reads paper-screen"),
        (dict(pretrain=5, demos="none"), "pre-training needs demonstrations"),
        (dict(demos="exact:3", demos_file="d.jsonl"), "give one"),
        (dict(steps=-1), "steps"),
        (dict(net="small", screen="strip"), "only the conv network"),
        (dict(preset="pixels", screen="paper", grid="7x5"), "square grid"),
        (dict(preset="pixels", screen="corner"), "screen goal"),
        (dict(stepz=1), "unknown setting"),
    ]:
        with pytest.raises(ValueError, match=says):
            blockstack.train_dqn(**kwargs)
    with pytest.raises(ValueError, match="cannot write"):
        blockstack.train_dqn(steps=10**9, out=str(tmp_path / "missing" / "n.safetensors"))
