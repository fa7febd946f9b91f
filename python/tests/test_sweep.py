"""The Ray sweep: a small grid of training runs on a local Ray with 2 CPUs."""

import csv
import hashlib
import json
import os

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


def test_a_config_that_is_a_pipe_a_device_or_too_large_is_refused_before_it_is_read(tmp_path):
    fifo = tmp_path / "c.toml"
    os.mkfifo(fifo)
    # No writer: opening the FIFO would wait for one; /dev/zero would be read until memory ran out.
    for path in ("/dev/zero", str(fifo)):
        with pytest.raises(ValueError, match="a pipe or a device, not a regular file"):
            sweep.read_config(path)
    big = tmp_path / "big.toml"
    big.write_bytes(b"#" * (3 << 20))
    with pytest.raises(ValueError, match="the most a sweep config can be"):
        sweep.read_config(str(big))


def test_a_run_is_keyed_by_the_contents_of_the_files_it_reads(tmp_path):
    demos = tmp_path / "demos.jsonl"
    demos.write_text("first")
    flags = {"demos_file": str(demos), "seed": 1}
    first = sweep.run_name("dqn", flags)
    assert sweep.run_name("dqn", flags) == first
    demos.write_text("second")
    assert sweep.run_name("dqn", flags) != first, "a changed file is a new run"
    # A run that reads no file keeps the name it had before files were keyed.
    old = hashlib.sha256(json.dumps({"command": "train", "flags": {"seed": 1}}, sort_keys=True).encode()).hexdigest()[:12]
    assert sweep.run_name("train", {"seed": 1}) == old
    with pytest.raises(ValueError, match="missing"):
        sweep.run_name("dqn", {"demos_file": str(tmp_path / "missing.jsonl")})


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
                                  "sweep": {"reward": ["sparse", "dense"]}}))
    out, storage = tmp_path / "results.csv", tmp_path / "runs"
    # Flags are checked before Ray starts; what fails in a run is its folder: here the dense
    # run's checkpoint is not a checkpoint.
    dense = next(f for f in sweep.runs(sweep.read_config(str(config))) if f["reward"] == "dense")
    (storage / sweep.run_name("train", dense)).mkdir(parents=True)
    (storage / sweep.run_name("train", dense) / "checkpoint.safetensors").write_text("not a checkpoint")
    assert sweep.main([str(config), "--num-cpus", "2", "--out", str(out), "--storage", str(storage)]) == 1
    captured = capsys.readouterr()
    assert "run reward=dense failed" in captured.err and "checkpoint.safetensors" in captured.err, captured.err
    rows = list(csv.DictReader(out.open()))
    assert [r["reward"] for r in rows] == ["sparse"]
    assert "sparse" in captured.out


def test_every_run_keeps_its_files_and_a_sweep_run_again_takes_them_up(tmp_path, capsys):
    pytest.importorskip("ray")
    config = tmp_path / "sweep.json"
    config.write_text(json.dumps({"train": {"blocks": 2, "goals": "0,1", "games": 60, "backend": "grid",
                                            "checkpoint_every": 25, "eval_episodes": 10},
                                  "sweep": {"seed": [1, 2], "gamma": [0.1, 0.9]}}))
    out, storage = tmp_path / "results.csv", tmp_path / "runs"
    argv = [str(config), "--num-cpus", "2", "--out", str(out), "--storage", str(storage)]
    assert sweep.main(argv) == 0
    first = out.read_text()
    rows = list(csv.DictReader(out.open()))
    assert len({r["run"] for r in rows}) == 4
    for row in rows:
        folder = storage / row["run"]
        assert {p.name for p in folder.iterdir()} == {"checkpoint.safetensors", "model.safetensors", "result.json"}
        assert int(row["resumed_at"]) == 0
    # The chart beside the table: one bar per gamma, over the seeds.
    assert (tmp_path / "results.png").stat().st_size > 0 and (tmp_path / "results.svg").stat().st_size > 0
    printed = capsys.readouterr().out
    assert sum(line.startswith("[") for line in printed.splitlines()) == 4, printed
    # Run again: every run is read from its folder, not trained again; the same table.
    for row in rows:
        (storage / row["run"] / "model.safetensors").unlink()
    assert sweep.main(argv) == 0
    assert out.read_text() == first
    assert not any((storage / r["run"] / "model.safetensors").exists() for r in rows)


def test_a_sweep_of_networks_names_its_command(tmp_path):
    config = tmp_path / "c.json"
    config.write_text(json.dumps({"train": {"command": "dqn", "preset": "dqn-planes", "steps": 10},
                                  "sweep": {"lr": [0.001, 0.0003]}}))
    runs = sweep.runs(sweep.read_config(str(config)))
    assert [r["lr"] for r in runs] == [0.001, 0.0003] and all("command" not in r for r in runs)
    assert sweep.command_of(sweep.read_config(str(config))) == "dqn"
    for bad, message in [
        ({"train": {"command": "tune"}}, "choose \"train\" or \"dqn\""),
        ({"train": {"command": "dqn", "games": 5}}, "unknown flag"),
        ({"train": {"out": "m.st"}}, "sets each run's files itself"),
        ({"sweep": {"command": ["train", "dqn"]}}, "command is not swept"),
    ]:
        config.write_text(json.dumps(bad))
        with pytest.raises(ValueError, match=message):
            sweep.runs(sweep.read_config(str(config)))


@pytest.mark.parametrize(
    "train, words",
    [
        ({"command": "dqn", "steps": 10, "demos_file": "missing.jsonl"}, "missing.jsonl"),
        ({"command": "dqn", "steps": 10, "demos_file": "/dev/zero"}, "a pipe or a device"),
        ({"command": "dqn", "steps": 10, "demos_file": "."}, "directory"),
        ({"command": "dqn", "preset": "dqn-planes", "blocks": 17}, "17"),
        ({"command": "train", "blocks": 17}, "17"),
        ({"command": "dqn", "preset": "general", "gamma": 0.5}, "gamma does not apply to the general preset"),
        ({"command": "dqn", "shiny": 1}, "unknown flag(s) shiny"),
        ({"command": "train", "shiny": 1}, "unknown flag(s) shiny"),
    ],
)
def test_a_sweeps_flags_and_files_are_refused_before_ray_starts(train, words, tmp_path, capsys, monkeypatch):
    def no_ray():
        raise AssertionError("Ray was started for a config that cannot run")

    monkeypatch.setattr(sweep._ray, "import_ray", no_ray)
    monkeypatch.chdir(tmp_path)
    config = tmp_path / "c.json"
    config.write_text(json.dumps({"train": train, "sweep": {"seed": [1, 2]}}))
    assert sweep.main([str(config), "--out", str(tmp_path / "r.csv")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and str(config) in err and words in err, err
    if "unknown" in words:
        listed = err.strip().split("the flags are ")[1].split(", ")
        assert "eval_episodes" in listed
        assert not set(listed) & {"out", "checkpoint", "resume", "check"}, listed
