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
