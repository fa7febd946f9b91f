"""Checkpoints from Python: ``blockstack.train(checkpoint=...)`` writes the file ``blockstack
train --checkpoint`` writes and goes on from one of its own run, so a run stopped and taken
up again (from Python or the command line) ends with the model a run that never stopped
ends with, byte for byte."""

import pytest

import blockstack

RUN = dict(blocks=2, goals="0,1:1,0", backend="grid", seed=5)


def test_a_tabular_run_goes_on_from_its_checkpoint(cli, tmp_path):
    whole, resumed, ck = tmp_path / "whole.st", tmp_path / "resumed.st", tmp_path / "ck"
    cli("train", "--blocks", "2", "--goals", "0,1:1,0", "--backend", "grid", "--seed", "5",
        "--games", "300", "--out", whole)
    # Half the run from the command line, the rest from Python.
    cli("train", "--blocks", "2", "--goals", "0,1:1,0", "--backend", "grid", "--seed", "5",
        "--games", "150", "--checkpoint", ck, "--checkpoint-every", "70", "--out", tmp_path / "half.st")
    row = blockstack.train(**RUN, games=300, checkpoint=str(ck), checkpoint_every=70, out=str(resumed))
    assert row["resumed_at"] == 150 and row["games"] == 300
    assert resumed.read_bytes() == whole.read_bytes()
    # Its checkpoint now holds the whole run: asked again, nothing is left to play.
    again = blockstack.train(**RUN, games=300, checkpoint=str(ck), out=str(resumed))
    assert again["resumed_at"] == 300
    assert resumed.read_bytes() == whole.read_bytes()


def test_a_checkpoint_of_another_run_is_refused(tmp_path):
    ck = tmp_path / "ck"
    blockstack.train(**RUN, games=20, checkpoint=str(ck))
    with pytest.raises(ValueError, match="other settings"):
        blockstack.train(**dict(RUN, seed=6), games=20, checkpoint=str(ck))
    with pytest.raises(ValueError, match="more than the 10 asked for"):
        blockstack.train(**RUN, games=10, checkpoint=str(ck))
    with pytest.raises(ValueError, match="checkpoint_every needs checkpoint"):
        blockstack.train(**RUN, games=10, checkpoint_every=5)
    with pytest.raises(ValueError, match="at least 1"):
        blockstack.train(**RUN, games=10, checkpoint=str(ck), checkpoint_every=0)


def test_a_network_run_writes_the_checkpoint_of_the_command_line(cli, tmp_path):
    flags = ["--preset", "dqn-planes", "--blocks", "2", "--goals", "0,1", "--hidden", "32", "--steps", "400",
             "--seed", "3"]
    by_cli, ck_cli = tmp_path / "cli.st", tmp_path / "cli.ck"
    cli("dqn", *flags, "--checkpoint", ck_cli, "--checkpoint-every", "150", "--out", by_cli)
    run = dict(preset="dqn-planes", blocks=2, goals="0,1", hidden=32, steps=400, seed=3)
    by_python, ck_python = tmp_path / "python.st", tmp_path / "python.ck"
    row = blockstack.train_dqn(**run, checkpoint=str(ck_python), checkpoint_every=150, out=str(by_python),
                               eval_episodes=5)
    assert row["resumed_at"] == 0 and row["eval_episodes"] == 5
    assert by_python.read_bytes() == by_cli.read_bytes()
    assert ck_python.read_bytes() == ck_cli.read_bytes()
    # The command line's checkpoint holds the whole run: taken up from Python, nothing is left.
    again = tmp_path / "again.st"
    assert blockstack.train_dqn(**run, checkpoint=str(ck_cli), out=str(again))["resumed_at"] == 400
    assert again.read_bytes() == by_cli.read_bytes()
    with pytest.raises(ValueError, match="other settings"):
        blockstack.train_dqn(**dict(run, seed=4), checkpoint=str(ck_cli))


@pytest.mark.parametrize(
    "trainer, run",
    [
        (blockstack.train, dict(RUN, games=10**9)),
        (blockstack.train_dqn, dict(blocks=2, goals="0,1", steps=10**9, demos="none", pretrain=0, backend="grid")),
    ],
    ids=["train", "train_dqn"],
)
def test_both_trainers_check_their_files_before_any_work(trainer, run, tmp_path):
    # A run of 10**9 games or steps: only a check before training ends these calls.
    ck, out = tmp_path / "ck", tmp_path / "out.st"
    with pytest.raises(ValueError, match="does not exist"):
        trainer(**run, out=str(tmp_path / "missing" / "out.st"))
    with pytest.raises(ValueError, match="does not exist"):
        trainer(**run, checkpoint=str(tmp_path / "missing" / "ck"))
    with pytest.raises(ValueError, match="also the input"):
        trainer(**run, checkpoint=str(out), out=str(out))
    with pytest.raises(ValueError, match="checkpoint_every needs checkpoint"):
        trainer(**run, checkpoint_every=5)
    with pytest.raises(ValueError, match="at least 1"):
        trainer(**run, checkpoint=str(ck), checkpoint_every=0)
    assert not ck.exists() and not out.exists()
