"""Bad arguments from Python: a ValueError naming the argument, never an OverflowError, a
PanicException or an abort; a refused call changes nothing.

Each case here raised OverflowError, a cryptic TypeError, was silently misread, or aborted
the interpreter before.
"""

import copy
import json
import pickle
import subprocess
import sys
import threading

import numpy as np
import pytest

import blockstack
from blockstack import _native
from blockstack.vector import StackVectorEnv


def run_python(script):
    """Runs ``script`` in a fresh interpreter: an abort there must not end pytest."""
    return subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300)


def test_sizes_beyond_memory_are_value_errors_not_aborts():
    script = (
        "import blockstack, blockstack._checks as c\n"
        "from blockstack.vector import StackVectorEnv\n"
        "c.memory_bytes = lambda: 16 * 2**30  # a 16 GiB machine, whatever this one is\n"
        "for name, call in [\n"
        "    ('num_envs=10000000', lambda: StackVectorEnv(10**7)),\n"
        "    ('num_envs=4611686018427387904', lambda: StackVectorEnv(2**62)),\n"
        "    ('episodes=1000000000', lambda: blockstack.demonstrations(10**9)),\n"
        "]:\n"
        "    try:\n"
        "        call()\n"
        "    except ValueError as e:\n"
        "        assert name in str(e) and 'GiB' in str(e), e\n"
        "        print('refused', name)\n"
        "        continue\n"
        "    raise SystemExit(name + ': accepted')\n"
    )
    run = run_python(script)
    assert run.returncode == 0, run.stderr
    assert run.stdout.count("refused") == 3


def test_2_to_the_62_environments_are_refused_on_any_machine():
    run = run_python(
        "from blockstack.vector import StackVectorEnv\n"
        "try:\n    StackVectorEnv(2**62)\nexcept ValueError as e:\n    print(e)\n"
    )
    assert run.returncode == 0, run.stderr
    assert "num_envs=" in run.stdout


def test_arrays_larger_than_the_bound_are_refused_before_they_are_made(tmp_path, cli):
    path = tmp_path / "t.jsonl"
    cli("run", "--episodes", "2", "--seed", "3", "--trajectory", path)
    assert len(blockstack.read_recording(path, obs="frame")["actions"]) > 0
    with pytest.raises(ValueError, match=r"steps as obs=frame make .* GiB of arrays"):
        _native.read_recording(str(path), "frame", "spec", 1000)


@pytest.mark.parametrize(
    "call, name",
    [
        (lambda: blockstack.StackEnv(horizon=-1), "horizon"),
        (lambda: blockstack.StackEnv(horizon=2**32), "horizon"),
        (lambda: blockstack.StackEnv(max_episode_steps=-5), "max_episode_steps"),
        (lambda: blockstack.StackEnv(blocks=-1), "blocks"),
        (lambda: StackVectorEnv(2, horizon=2**32), "horizon"),
        (lambda: StackVectorEnv(-1), "num_envs"),
        (lambda: StackVectorEnv(2, blocks=-1), "blocks"),
        (lambda: blockstack.demonstrations(-1), "episodes"),
        (lambda: blockstack.demonstrations(1, seed=-1), "seed"),
        (lambda: blockstack.train(seed=-1), "seed"),
        (lambda: blockstack.train(blocks=-1), "blocks"),
        (lambda: blockstack.train(horizon=2**32), "horizon"),
        (lambda: blockstack.train(games=-1), "games"),
        (lambda: blockstack.train(eval_episodes=-1), "eval_episodes"),
        (lambda: blockstack.train(gamess=1), "gamess"),
    ],
)
def test_integers_out_of_range_are_value_errors_naming_the_argument(call, name):
    with pytest.raises(ValueError, match=name):
        call()


@pytest.mark.parametrize(
    "call, says",
    [
        # Each of these raised OverflowError or TypeError from the native side, naming nothing.
        (lambda: blockstack.solve([(300, 0), (1, 0)], "0,1"), "cells\\[0\\] x"),
        (lambda: blockstack.solve([(0, 0), (1, 0)], "0,1", held=-1), "held"),
        (lambda: blockstack.solve([(0, 0), (1, 0)], "0,1", solver=3), "solver"),
        (lambda: blockstack.solve([(0, 0), ("a", 0)], "0,1"), "cells\\[1\\] x"),
        (lambda: blockstack.episode_seed(-1, 0), "base"),
        (lambda: blockstack.episode_seed(0, 2**64), "index"),
        (lambda: blockstack.StackEnv(obs=3), "obs"),
        (lambda: blockstack.StackEnv(backend=None), "backend"),
        (lambda: blockstack.demonstrations(1, expert=None), "expert"),
        (lambda: blockstack.read_recording(3), "path"),
        (lambda: blockstack.read_recording("x.jsonl", obs=3), "obs"),
        (lambda: blockstack.load(3), "path"),
    ],
)
def test_wrong_types_are_value_errors_naming_the_argument(call, says):
    with pytest.raises(ValueError, match=says):
        call()


def test_an_action_out_of_range_says_so():
    env = blockstack.StackEnv()
    env.reset(seed=1)
    with pytest.raises(ValueError, match=f"action {2**70} is out of range"):
        env.step(2**70)
    with pytest.raises(ValueError, match="action -1 is out of range"):
        env.step(-1)
    venv = StackVectorEnv(2)
    venv.reset(seed=1)
    with pytest.raises(ValueError, match=f"action {2**64 - 1} is out of range"):
        venv.step(np.array([0, 2**64 - 1], dtype=np.uint64))


def test_reset_options_are_checked_and_a_refused_reset_changes_nothing():
    env = blockstack.StackEnv(obs="state", goal="0,1,2")
    env.reset(seed=4)
    env.step(5)
    before = (env.state(), env.unwrapped._native.steps)
    for options, needle in [
        ({"cell": [(0, 0), (2, 0), (4, 0)]}, "unknown reset option"),
        ({"goal": "0,1,2"}, "need \"cells\""),
        ({"held": 1}, "need \"cells\""),
        ({"cells": [(0, 0), (2, 0), (4, 0)], "held": -1}, "held"),
        ({"cells": [(0, 0), (0, 1), (0, 2)], "goal": "0,1,2"}, "already holds"),
        ({"cells": [(0, 0), (2, 0), (4, 0)], "goal": (1.5, 0, 2)}, "1.5"),
        ({"cells": [(0, 0), (2, 0), (4, 0)], "goal": [True, False, 2]}, "True"),
        ({"cells": [(0, 0), (2, 0), (4, 0)], "goal": b"1,0,2"}, "bytes"),
    ]:
        with pytest.raises(ValueError, match=needle):
            env.reset(options=options)
        assert (env.state(), env.unwrapped._native.steps) == before, options


def test_goals_that_are_not_block_ids_are_refused_everywhere():
    for goal in [(1.5, 0, 2), [True, False, 2], b"1,0,2"]:
        with pytest.raises(ValueError, match="a goal is text"):
            blockstack.StackEnv(goal=goal)
        with pytest.raises(ValueError, match="a goal is text"):
            StackVectorEnv(2, goal=goal)


@pytest.mark.parametrize("grid", ["5x4", (5, 4), [5, 4]])
def test_a_grid_is_text_or_a_pair_everywhere(grid):
    assert blockstack.StackEnv(grid=grid).unwrapped._native.grid == (5, 4)
    assert StackVectorEnv(2, grid=grid).single_observation_space.shape == blockstack.StackEnv(grid=(5, 4)).observation_space.shape
    assert len(blockstack.demonstrations(1, grid=grid, backend="grid")["actions"]) > 0
    with pytest.raises(ValueError, match="grid"):
        blockstack.StackEnv(grid="seven")


def test_the_autoreset_mode_is_taken_as_the_error_message_spells_it():
    assert StackVectorEnv(2, autoreset_mode="same-step").autoreset_mode.value == "SameStep"
    assert StackVectorEnv(2, autoreset_mode="SameStep").autoreset_mode.value == "SameStep"
    with pytest.raises(ValueError, match="use next-step or same-step"):
        StackVectorEnv(2, autoreset_mode="sometimes")


def test_one_vector_env_stepped_from_two_threads_takes_turns():
    venv = StackVectorEnv(64, backend="grid", threads=2)
    venv.reset(seed=1)
    errors = []

    def work():
        try:
            for _ in range(200):
                venv.step(np.zeros(64, dtype=np.int64))
        except Exception as e:  # noqa: BLE001 - any error is the failure reported below
            errors.append(e)

    threads = [threading.Thread(target=work) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert errors == []


def test_pickle_and_deepcopy_are_refused_clearly():
    for env in (blockstack.StackEnv(), StackVectorEnv(2)):
        for attempt in (lambda: pickle.dumps(env), lambda: copy.deepcopy(env), lambda: copy.copy(env)):
            with pytest.raises(TypeError, match="cannot be pickled or copied"):
                attempt()


def test_sweep_configs_that_are_not_tables_are_one_line_errors(tmp_path, capsys):
    from blockstack import sweep

    for name, text, needle in [
        ("a.toml", "train = 5\n", "train must be a table"),
        ("b.json", "5", "a sweep config is a table"),
        ("c.json", json.dumps({"train": [1, 2]}), "train must be a table"),
        ("d.toml", "[train\n", "d.toml: "),
        ("e.json", "{", "e.json: "),
        ("f.json", json.dumps({"sweep": {f"f{i}": list(range(10)) for i in range(9)}}), "1,000,000,000 combinations"),
        ("g.json", json.dumps({"train": {"seed": -1}, "sweep": {"gamma": [0.1]}}), "seed=-1 is out of range"),
        ("h.json", json.dumps({"train": {"gamess": 1}, "sweep": {"gamma": [0.1]}}), "unknown flag(s) gamess"),
    ]:
        path = tmp_path / name
        path.write_text(text)
        assert sweep.main([str(path), "--out", str(tmp_path / "r.csv")]) == 2, name
        err = capsys.readouterr().err
        assert needle in err and err.count("\n") == 1 and "Traceback" not in err, (name, err)
    assert sweep.main([str(tmp_path / "g.json"), "--num-cpus", "0"]) == 2
    assert "--num-cpus" in capsys.readouterr().err


@pytest.mark.parametrize(
    "call",
    [
        "blockstack.train(blocks=2, goals='0,1', games=10**9, backend='grid')",
        "blockstack.train_dqn(blocks=2, goals='0,1', steps=10**9, demos='none', pretrain=0, backend='grid')",
        "blockstack.demonstrations(10**6, blocks=2, backend='grid')",
        # Training done at once, then a long evaluation.
        "blockstack.train(blocks=2, goals='0,1', games=1, backend='grid', eval_episodes=10**7)",
    ],
)
def test_ctrl_c_stops_a_long_native_call(call):
    script = (
        "import os, signal, threading, time, blockstack\n"
        # A shell that starts a job in the background without job control hands it SIGINT
        # ignored, and Python keeps that: put back the handler that raises KeyboardInterrupt.
        "signal.signal(signal.SIGINT, signal.default_int_handler)\n"
        "threading.Timer(1.0, lambda: os.kill(os.getpid(), signal.SIGINT)).start()\n"
        "start = time.monotonic()\n"
        "try:\n"
        f"    {call}\n"
        "except KeyboardInterrupt:\n"
        "    print('interrupted after', time.monotonic() - start)\n"
    )
    run = run_python(script)
    assert run.returncode == 0, run.stderr
    assert "interrupted" in run.stdout, run.stdout


@pytest.mark.parametrize(
    "cli_args, python_call",
    [
        (["run", "--grid", "7by7"], lambda: blockstack.StackEnv(grid="7by7")),
        (["run", "--view", "front"], lambda: blockstack.StackEnv(view="front")),
        (["run", "--backend", "box2d"], lambda: blockstack.StackEnv(backend="box2d")),
        (["run", "--reward", "lots"], lambda: blockstack.StackEnv(reward="lots")),
        (["run", "--view", "side", "--goal", "0,1//2"], lambda: blockstack.BlocksWorldEnv(goal="0,1//2")),
        (["run", "--profile", "paper"], lambda: blockstack.StackEnv(profile="paper")),
        (
            ["solve", "--start", "0,0;3,0;5,2", "--goal", "1,0,2", "--solver", "greedy"],
            lambda: blockstack.solve([(0, 0), (3, 0), (5, 2)], "1,0,2", solver="greedy"),
        ),
        (
            ["solve", "--start", "0,0;3,0;5,2", "--goal", "1,0,2", "--solver", "near-optimal"],
            lambda: blockstack.solve([(0, 0), (3, 0), (5, 2)], "1,0,2", solver="near-optimal"),
        ),
    ],
)
def test_python_and_the_cli_say_the_same_of_the_same_bad_input(cli, cli_args, python_call):
    import subprocess

    with pytest.raises(ValueError) as python:
        python_call()
    with pytest.raises(subprocess.CalledProcessError) as run:
        cli(*cli_args)
    assert run.value.returncode == 2
    assert run.value.stderr.count("\n") == 1, run.value.stderr
    assert str(python.value) in run.value.stderr, (str(python.value), run.value.stderr)
