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
