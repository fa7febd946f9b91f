"""The readers of the CLI's files refuse what the CLI refuses, with its message, as ValueError.

``read_recording`` runs the checked reader of each format (the one ``blockstack dqn
--demos-file`` runs): every case here was accepted, or crashed the interpreter, before.
"""

import json
import os
import pathlib
import subprocess
import sys

import pytest

import blockstack

ROOT = pathlib.Path(__file__).resolve().parents[2]
FIXTURES = ROOT / "testkit" / "fixtures"
OBS = ("planes", "role-planes", "state", "frame", "paper-screen")


def lines(name):
    return (FIXTURES / name).read_text().splitlines()


def write(path, rows):
    path.write_text("".join((r if isinstance(r, str) else json.dumps(r)) + "\n" for r in rows))
    return path


def refused(path, needle, obs=OBS):
    for kind in obs:
        with pytest.raises(ValueError, match=needle):
            blockstack.read_recording(path, obs=kind)


EPISODE = {"type": "episode", "episode": 0, "seed": 1, "grid": [7, 7], "goal": [0, 1, 2], "horizon": 100,
           "start": [[0, 0], [2, 0], [4, 0]]}


def step(n, action, blocks, held, reward=0.0, terminated=False):
    return {"type": "step", "episode": 0, "step": n, "action": action, "blocks": blocks, "held": held,
            "reward": reward, "terminated": terminated, "truncated": False}


PICK0 = step(1, 5, [[0, 0], [2, 0], [4, 0]], 0)


def test_a_hand_made_trajectory_that_keeps_the_rules_reads(tmp_path):
    d = blockstack.read_recording(write(tmp_path / "t.jsonl", [EPISODE, PICK0, step(2, 0, [[0, 1], [2, 0], [4, 0]], 0)]),
                                  obs="state")
    assert list(d["actions"]) == [5, 0]


def test_a_block_that_jumps_three_cells_on_one_up_is_refused(tmp_path):
    refused(write(tmp_path / "t.jsonl", [EPISODE, PICK0, step(2, 0, [[0, 3], [2, 0], [4, 0]], 0)]), "line 3")


def test_an_action_that_does_not_match_the_state_change_is_refused(tmp_path):
    refused(write(tmp_path / "t.jsonl", [EPISODE, PICK0, step(2, 3, [[0, 1], [2, 0], [4, 0]], 0)]), "line 3")


def test_an_invented_reward_or_termination_is_refused(tmp_path):
    refused(write(tmp_path / "r.jsonl", [EPISODE, dict(PICK0, reward=5.0)]), "line 2: the reward 5")
    refused(write(tmp_path / "t.jsonl", [EPISODE, dict(PICK0, terminated=True)]), "line 2: .*terminated")


def test_steps_after_a_terminated_step_are_refused(tmp_path):
    rows = lines("trajectory.jsonl")
    end = next(i for i, r in enumerate(rows) if '"terminated":true' in r)
    after = json.loads(rows[end])
    after["step"] += 1
    after["action"] = 7  # picking the held block again: allowed, and changes nothing
    refused(write(tmp_path / "t.jsonl", rows[:end + 1] + [after]), f"line {end + 2}")


def test_a_first_step_not_from_the_episodes_start_is_refused(tmp_path):
    rows = lines("recording-v2.jsonl")
    first = json.loads(rows[2])
    first["state"]["blocks"][0] = [1, 1]
    first["next"]["blocks"][0] = [1, 1]
    refused(write(tmp_path / "r.jsonl", rows[:2] + [first] + rows[3:]), "line 3: .*start")


def test_the_same_episode_twice_is_refused(tmp_path):
    rows = lines("trajectory.jsonl")
    second = next(i for i, r in enumerate(rows) if i > 0 and '"type":"episode"' in r)
    refused(write(tmp_path / "t.jsonl", rows[:second] + rows[:second]), f"line {second + 1}")
    rows = lines("recording-v2.jsonl")
    second = next(i for i, r in enumerate(rows) if i > 1 and '"type":"episode"' in r)
    refused(write(tmp_path / "r.jsonl", rows[:second] + rows[1:second]), f"line {second + 1}")


def test_a_recorded_pick_whose_next_state_moves_a_block_is_refused(tmp_path):
    rows = lines("recording-v2.jsonl")
    pick = json.loads(rows[2])
    assert pick["action"] == "pick 0"
    pick["next"]["blocks"][0] = [1, 1]
    refused(write(tmp_path / "r.jsonl", rows[:2] + [pick] + rows[3:]), "line 3: .*rules")


def test_a_cell_just_outside_the_grid_is_refused(tmp_path):
    refused(write(tmp_path / "t.jsonl", [EPISODE, step(1, 5, [[0, 7], [2, 0], [4, 0]], 0)]), "line 2: .*outside")


def test_sessions_of_other_worlds_appended_to_one_file_are_value_errors(cli, tmp_path):
    for name, world in (("blocks", ["--blocks", "2", "--goals", "0,1"]), ("grid", ["--grid", "5x5", "--goals", "0,1,2"])):
        record = tmp_path / f"{name}.jsonl"
        record.write_text((FIXTURES / "recording-v2.jsonl").read_text())
        model = tmp_path / f"{name}.safetensors"
        cli("train", "--games", "5", *world, "--out", model)
        goals = world[world.index("--goals") + 1]
        cli("correct", "--model", model, "--demonstrator", "1", "--demos", "1", "--goals", goals,
            "--out", tmp_path / "c.safetensors", "--record", record)
        refused(record, "line 25: .*one world")


def test_a_hand_edited_extra_or_missing_block_is_a_value_error(tmp_path):
    rows = lines("recording-v2.jsonl")
    for edit in (lambda b: b + [[3, 3]], lambda b: b[:-1]):
        s = json.loads(rows[2])
        s["state"]["blocks"] = edit(s["state"]["blocks"])
        s["next"]["blocks"] = edit(s["next"]["blocks"])
        refused(write(tmp_path / "r.jsonl", rows[:2] + [s] + rows[3:]), "line 3")
        refused(write(tmp_path / "t.jsonl", [EPISODE, dict(PICK0, blocks=edit(PICK0["blocks"]))]), "line 2")


def test_a_device_or_a_fifo_is_refused_before_it_is_read(tmp_path):
    fifo = tmp_path / "f.jsonl"
    os.mkfifo(fifo)
    # No writer: opening the FIFO would wait for one; it is refused at once instead.
    for path in ("/dev/zero", fifo):
        with pytest.raises(ValueError, match="a pipe or a device, not a regular file"):
            blockstack.read_recording(path)


def test_trajectories_and_recordings_share_one_line_bound(tmp_path):
    long = json.dumps(EPISODE).replace('"type"', " " * 70_000 + '"type"', 1)
    refused(write(tmp_path / "t.jsonl", [long, PICK0]), "line 1: the line is longer than 64 KiB", obs=("state",))
    rows = lines("recording-v2.jsonl")
    long = rows[2].replace('"type"', " " * 70_000 + '"type"', 1)
    refused(write(tmp_path / "r.jsonl", rows[:2] + [long] + rows[3:]), "line 3: the line is longer", obs=("state",))


def test_files_written_by_the_previous_release_still_read():
    for name in ("trajectory.jsonl", "trajectory-original.jsonl", "trajectory-paper.jsonl",
                 "trajectory-dense.jsonl", "recording-v2.jsonl", "recording-original-v2.jsonl"):
        for kind in OBS:
            d = blockstack.read_recording(FIXTURES / name, obs=kind)
            steps = sum('"type":"step"' in r for r in lines(name))
            assert len(d["actions"]) == steps, name


def test_python_refuses_with_the_clis_message(tmp_path):
    bad = write(tmp_path / "t.jsonl", [EPISODE, PICK0, step(2, 0, [[0, 3], [2, 0], [4, 0]], 0)])
    with pytest.raises(ValueError) as python:
        blockstack.read_recording(bad)
    binary = pathlib.Path(os.environ.get("BLOCKSTACK_BIN", ROOT / "target" / "release" / "blockstack"))
    cli = subprocess.run([str(binary), "dqn", "--demos-file", str(bad), "--out", str(tmp_path / "n.safetensors")],
                         capture_output=True, text=True)
    assert cli.returncode == 2
    assert str(python.value) in cli.stderr, (str(python.value), cli.stderr)


BAD_INPUTS = [
    "", "\n", "not json\n", "{}\n", '{"type":"step"}\n', "\x00\x01\x02",
    json.dumps(dict(EPISODE, grid=[0, 7])) + "\n",
    json.dumps(dict(EPISODE, grid=[2 ** 40, 7])) + "\n",
    json.dumps(dict(EPISODE, start=[[0, 0]])) + "\n",
    json.dumps(dict(EPISODE, horizon=0)) + "\n",
    json.dumps(EPISODE) + "\n" + json.dumps(dict(PICK0, action=2 ** 64)) + "\n",
    json.dumps(EPISODE) + "\n" + json.dumps(dict(PICK0, held=255)) + "\n",
    json.dumps(EPISODE) + "\n" + json.dumps(dict(PICK0, reward=float("nan"))).replace("NaN", "1e999") + "\n",
    '{"type":"session","format":"blockstack-demos","version":2,"grid":[7,7],"blocks":300,"rule":{"margin":null,"learn_agent_steps":true},"demonstrator":"x","model":null,"model_id":"0"}\n',
]


def test_no_bad_input_crashes_the_interpreter(tmp_path):
    """Every bad input is a ValueError, in a subprocess: an abort or a PanicException (a
    BaseException) would end it otherwise."""
    paths = [str(write(tmp_path / f"bad{i}.jsonl", [text.rstrip("\n")] if text else [])) for i, text in enumerate(BAD_INPUTS)]
    script = (
        "import sys, blockstack\n"
        "for p in sys.argv[1:]:\n"
        "    for obs in ('planes', 'role-planes', 'state', 'frame', 'paper-screen'):\n"
        "        try:\n"
        "            blockstack.read_recording(p, obs=obs)\n"
        "        except ValueError:\n"
        "            continue\n"
        "        raise SystemExit(f'{p} {obs}: accepted')\n"
    )
    run = subprocess.run([sys.executable, "-c", script, *paths], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
