"""The Ray sweep: a small grid of training runs on a local Ray with 2 CPUs."""

import csv
import json

import pytest

import blockstack
from blockstack import sweep


def test_train_runs_the_rust_trainer_in_process():
    a = blockstack.train(blocks=2, goals="0,1", games=30, seed=3, backend="grid", eval_episodes=10)
    b = blockstack.train(blocks=2, goals="0,1", games=30, seed=3, backend="grid", eval_episodes=10)
    a.pop("train_seconds"), b.pop("train_seconds")
    assert a == b, "the same config gives the same run"
    assert a["games"] == 30 and a["eval_episodes"] == 10 and a["repr"] == "chasing"
    with pytest.raises(ValueError, match="cannot read reward"):
        blockstack.train(reward="shiny")
    with pytest.raises(ValueError, match="not a permutation"):
        blockstack.train(goals="0,0,1")


def test_train_under_the_original_profile_takes_the_papers_learner_as_coded():
    run = blockstack.train(profile="original", blocks=2, goals="0,1", games=3, seed=1, eval_episodes=5)
    assert run["profile"] == "original"
    assert run["repr"] == "chasing-code" and run["reward"] == "paper-code"
    assert run["games"] == 3 and run["eval_episodes"] == 5
    with pytest.raises(ValueError, match="profile"):
        blockstack.train(profile="nope")


def test_a_config_expands_to_every_combination(tmp_path):
    path = tmp_path / "c.json"
    path.write_text(json.dumps({"train": {"games": 5, "final-replay": True}, "sweep": {"seed": [1, 2], "gamma": [0.1, 0.9]}}))
    runs = sweep.runs(sweep.read_config(str(path)))
    assert len(runs) == 4
    assert {(r["seed"], r["gamma"]) for r in runs} == {(1, 0.1), (1, 0.9), (2, 0.1), (2, 0.9)}
    assert all(r["final_replay"] and r["games"] == 5 for r in runs)


def test_a_small_sweep_runs_on_a_local_ray_with_two_cpus(tmp_path):
    pytest.importorskip("ray")
    config = tmp_path / "sweep.toml"
    config.write_text(
        '[train]\nblocks = 2\ngoals = "0,1"\ngames = 40\nbackend = "grid"\neval_episodes = 20\n'
        "[sweep]\nseed = [1, 2]\ngamma = [0.1, 0.9]\n"
    )
    out = tmp_path / "results.csv"
    assert sweep.main([str(config), "--num-cpus", "2", "--out", str(out)]) == 0
    rows = list(csv.DictReader(out.open()))
    assert len(rows) == 4
    assert list(rows[0])[:2] == ["seed", "gamma"]
    for row in rows:
        alone = blockstack.train(blocks=2, goals="0,1", games=40, backend="grid", eval_episodes=20,
                                 seed=int(row["seed"]), gamma=float(row["gamma"]))
        assert int(row["successes"]) == alone["successes"]
        assert int(row["eval_failures"]) == alone["eval_failures"]


def test_an_unwritable_table_is_refused_before_any_run(tmp_path, capsys):
    config = tmp_path / "c.json"
    config.write_text(json.dumps({"train": {"games": 5}, "sweep": {"seed": [1]}}))
    assert sweep.main([str(config), "--out", str(tmp_path / "missing" / "r.csv")]) == 2
    assert "does not exist" in capsys.readouterr().err


def test_a_failed_run_keeps_the_finished_ones_and_is_named(tmp_path, capsys):
    pytest.importorskip("ray")
    config = tmp_path / "sweep.json"
    config.write_text(json.dumps({"train": {"blocks": 2, "goals": "0,1", "games": 5, "backend": "grid"},
                                  "sweep": {"reward": ["sparse", "shiny"]}}))
    out = tmp_path / "results.csv"
    assert sweep.main([str(config), "--num-cpus", "2", "--out", str(out)]) == 1
    captured = capsys.readouterr()
    assert "run reward=shiny failed" in captured.err and "cannot read reward" in captured.err
    rows = list(csv.DictReader(out.open()))
    assert [r["reward"] for r in rows] == ["sparse"]
    assert "sparse" in captured.out
