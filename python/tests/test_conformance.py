"""The conformance suite: every promise the library makes, over every world and every front
end that offers it, so that a capability wired in at one edge and forgotten at another fails
here, not in a user's hands.

The worlds are every registered id crossed with the world keywords that change the rules:
``profile`` (spec, original), ``protocol`` (free, paper), ``view`` (top, side), ``actions``
(gripper, moves) and ``pddl=``. A combination an id refuses is listed with the words it is
refused in (:data:`REFUSED`); every other one is a world of :data:`WORLDS`. The contracts:

- **Gymnasium's**: ``check_env`` passes with no warning; ``step`` takes every element of the
  action space; an action the rules refuse changes nothing, counts as a step, gets the
  world's reward for a step that changes nothing and says ``info["illegal"]``, where
  ``strict=True`` raises; every other step is the strict environment's. The vector env steps
  as ``SyncVectorEnv`` of the same environments does, refused actions included.
- **The expert's**: in every world the expert (``expert_action``) is legal in every state it
  meets, reaches the goal, and takes as few steps as a breadth-first search over the world's
  own legal actions; ``optimal_steps`` says that number, and ``demonstrations`` plays it.
- **CLI = Python**: ``blockstack run --agent exact`` plays, step for step, what the Python
  environment's expert plays from the same seeds; ``solve_pddl`` and ``solve_all`` give what
  ``blockstack solve --pddl`` and ``solve-all`` give, for every planner, with the domain file
  of either spelling or none, and the plan file written by either is the same.
- **Files**: every reader, in the CLI and in Python, refuses a FIFO or a device at once, and
  no trainer's checkpoint writes over a trained model.
- **Default play**: a model of every kind (``q``, ``dqn``, ``relational``) plays by default
  with its own epsilon (its profile's test policy; greedy for a relational policy), reward
  and world, the same in ``run``, ``eval`` and Python's ``load(...)``: leaving them out
  plays what naming the model's own plays.

Breaking any one of them (a protocol the expert ignores, a refused action that raises, a
reader that opens before it looks) fails a test here.
"""

from __future__ import annotations

import collections
import dataclasses
import json
import os
import subprocess
import sys
import warnings
from typing import Optional

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from gymnasium.vector import AutoresetMode, SyncVectorEnv

import blockstack
from blockstack.vector import StackVectorEnv

#: A small Blocks World task: c on a, b alone; the goal a on b on c.
TASK = """(define (problem conformance) (:domain blocksworld) (:objects a b c)
 (:init (arm-empty) (clear c) (on c a) (on-table a) (clear b) (on-table b))
 (:goal (and (on a b) (on b c) (on-table c))))
"""


@dataclasses.dataclass(frozen=True)
class World:
    """One world: a registered id and the keywords that make it."""

    env_id: str
    keywords: tuple  # (name, value) pairs, hashable for pytest's ids

    @property
    def kwargs(self) -> dict:
        return dict(self.keywords)

    @property
    def name(self) -> str:
        return self.env_id.split("/")[1] + "(" + ", ".join(f"{k}={v}" for k, v in self.keywords) + ")"

    @property
    def view(self) -> str:
        return "side" if self.env_id == blockstack.BLOCKS_WORLD_ID else self.kwargs.get("view", "top")

    @property
    def moves(self) -> bool:
        return self.kwargs.get("actions") == "moves"

    def make(self, task: Optional[str] = None, **extra):
        kwargs = dict(self.kwargs, backend="grid", **extra)
        if kwargs.pop("pddl", None):
            kwargs["pddl"] = task
        elif self.env_id != blockstack.GOAL_ENV_ID:
            kwargs.setdefault("blocks", 2 if self.view == "top" else 3)
        else:
            kwargs.setdefault("blocks", 2)
        return gym.make(self.env_id, **kwargs).unwrapped


def _combinations():
    """Every id with every value of the keywords it takes: ``(id, keywords)``."""
    ids = {
        blockstack.ENV_ID: ("profile", "protocol", "view", "actions"),
        blockstack.BLOCKS_WORLD_ID: ("profile", "protocol", "actions", "pddl"),
        blockstack.GOAL_ENV_ID: ("profile", "protocol", "view"),
    }
    values = {
        "profile": ("spec", "original"),
        "protocol": ("free", "paper"),
        "view": ("top", "side"),
        "actions": ("gripper", "moves"),
        "pddl": (False, True),
    }
    for env_id, names in ids.items():
        for chosen in __import__("itertools").product(*(values[n] for n in names)):
            keywords = tuple((n, v) for n, v in zip(names, chosen) if not (n == "pddl" and not v))
            yield env_id, keywords


def _refusal(env_id: str, kw: dict) -> Optional[str]:
    """The words a combination is refused in, or ``None`` for a world."""
    side = env_id == blockstack.BLOCKS_WORLD_ID or kw.get("view") == "side"
    if kw.get("actions") == "moves" and not side:
        return 'needs view="side"'
    if kw.get("profile") == "original" and side:
        # The authors' start rule places blocks in the air: the side view starts from towers.
        return "the paper start rule places blocks in the air"
    return None


WORLDS = [World(i, k) for i, k in _combinations() if _refusal(i, dict(k)) is None]
REFUSED = [(World(i, k), _refusal(i, dict(k))) for i, k in _combinations() if _refusal(i, dict(k))]


@pytest.fixture(scope="module")
def task(tmp_path_factory) -> str:
    path = tmp_path_factory.mktemp("conformance") / "task.pddl"
    path.write_text(TASK)
    return str(path)


def by_name(worlds):
    return pytest.mark.parametrize("world", worlds, ids=[w.name for w in worlds])


def test_the_matrix_holds_every_world_and_names_every_refusal():
    # 16 + 16 + 8 combinations, 8 + 8 + 6 of them worlds; a new keyword value grows these and
    # the suite with them.
    assert len(WORLDS) + len(REFUSED) == 40
    assert len(WORLDS) == 22
    assert {w.env_id for w in WORLDS} == {blockstack.ENV_ID, blockstack.BLOCKS_WORLD_ID, blockstack.GOAL_ENV_ID}


@pytest.mark.parametrize("world, words", REFUSED, ids=[w.name for w, _ in REFUSED])
def test_a_combination_no_world_has_is_refused_in_one_line(world, words, task):
    with pytest.raises(ValueError) as e:
        world.make(task)
    assert words in str(e.value) and "\n" not in str(e.value)


# Gymnasium's contract ----------------------------------------------------------------------


@by_name(WORLDS)
def test_check_env_passes_with_no_warning(world, task):
    env = world.make(task)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env, skip_render_check=True)
    assert [str(w.message) for w in caught] == []


def _native(env):
    """The native environment under a Gymnasium class (the goal environment wraps one)."""
    return env._native if hasattr(env, "_native") else env._env._native


def _state(env):
    cells, held, goal = _native(env).state()
    return {"cells": [tuple(c) for c in cells], "held": held, "goal": list(goal)}


def _same(a, b) -> bool:
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    return np.array_equal(np.asarray(a), np.asarray(b))


@by_name(WORLDS)
def test_every_action_of_the_space_is_taken_and_a_refused_one_changes_nothing(world, task):
    env = world.make(task)
    strict = world.make(task, strict=True)
    env.action_space.seed(3)
    env.reset(seed=3)
    refused = taken = 0
    for _ in range(150):
        action = env.action_space.sample()
        before = _state(env)
        steps = _native(env).steps
        strict.reset(options=before)
        try:
            expected = strict.step(action)
        except ValueError as e:
            expected = e
        obs, reward, terminated, truncated, info = env.step(action)
        if isinstance(expected, ValueError):
            refused += 1
            assert info["illegal"] and _state(env) == before, (world.name, action)
            assert _native(env).steps == steps + 1, "a refused action counts towards the horizon"
            assert not terminated
        else:
            taken += 1
            assert not info["illegal"]
            e_obs, e_reward, e_terminated, e_truncated, e_info = expected
            assert _same(obs, e_obs) and reward == e_reward and terminated == e_terminated
            assert info["action_mask"].tolist() == e_info["action_mask"].tolist()
        if terminated or truncated:
            env.reset()
    assert taken > 0
    if world.kwargs["protocol"] == "paper" or world.moves:
        assert refused > 0, "the sample holds actions the rules refuse"


@by_name([w for w in WORLDS if w.env_id == blockstack.ENV_ID and not w.moves])
@pytest.mark.parametrize("mode", [AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP])
def test_the_vector_env_steps_as_sync_vector_env_refused_actions_included(world, mode):
    kwargs = dict(world.kwargs, backend="grid", blocks=2, horizon=25)
    kwargs.pop("actions")
    native = StackVectorEnv(3, autoreset_mode=mode, **kwargs)
    sync = SyncVectorEnv([lambda: blockstack.StackEnv(**kwargs) for _ in range(3)], autoreset_mode=mode)
    a, _ = native.reset(seed=9)
    b, _ = sync.reset(seed=9)
    assert np.array_equal(a, b)
    rng = np.random.default_rng(1)
    illegal = 0
    for _ in range(80):
        actions = rng.integers(0, native.single_action_space.n, size=3)
        got = native.step(actions)
        want = sync.step(actions)
        for x, y in zip(got[:4], want[:4]):
            assert np.array_equal(x, y)
        assert np.array_equal(got[4]["illegal"], want[4]["illegal"])
        illegal += int(got[4]["illegal"].sum())
    if world.kwargs["protocol"] == "paper":
        assert illegal > 0


# The expert's contract ---------------------------------------------------------------------


def _shortest(world, task, start) -> int:
    """Breadth-first search over the world's own legal actions (its mask) from ``start``:
    the fewest steps to a step that ends the episode at the goal."""
    probe = world.make(task, strict=True, horizon=10_000)
    key = lambda s: (tuple(s["cells"]), s["held"])  # noqa: E731
    seen = {key(start)}
    frontier = [start]
    for depth in range(1, 60):
        nxt = []
        for state in frontier:
            _, info = probe.reset(options=state)
            for action in np.flatnonzero(info["action_mask"]):
                probe.reset(options=state)
                _, _, terminated, _, _ = probe.step(int(action))
                if terminated:
                    return depth
                after = _state(probe)
                if key(after) not in seen:
                    seen.add(key(after))
                    nxt.append(after)
        frontier = nxt
    raise AssertionError("no plan within 60 steps")


@by_name(WORLDS)
def test_the_expert_is_legal_reaches_the_goal_and_takes_the_fewest_steps(world, task):
    env = world.make(task, horizon=500)
    for seed in (1, 2):
        _, info = env.reset(seed=seed)
        start = _state(env)
        fewest = _shortest(world, task, start)
        assert env.optimal_steps() == fewest
        steps = 0
        while True:
            action = env.expert_action()
            assert info["action_mask"][action], (world.name, start, steps, action)
            _, _, terminated, truncated, info = env.step(action)
            steps += 1
            assert not info["illegal"]
            if terminated or truncated:
                break
        assert terminated and steps == fewest, (world.name, start, steps, fewest)


# CLI = Python ------------------------------------------------------------------------------


#: Every expert by the name ``run --agent`` and ``demonstrations(expert=...)`` take, by view.
EXPERTS = {"top": ("exact", "oracle"), "side": ("exact", "exact-moves", "near-optimal", "oracle")}

#: The gripper worlds that ``demonstrations`` plays (it takes world keywords, not a task).
DEMONSTRATED = [
    (w, e)
    for w in WORLDS
    if w.env_id != blockstack.GOAL_ENV_ID and not w.moves and "pddl" not in w.kwargs
    for e in EXPERTS[w.view]
]


def _cli_episodes(cli, tmp_path, agent, flags, episodes, seed) -> dict:
    """Each episode ``blockstack run --agent AGENT`` plays: its ``(action, reward)`` steps."""
    out = tmp_path / f"{agent}.jsonl"
    cli("run", "--agent", agent, "--episodes", episodes, "--seed", seed, "--trajectory", out, *flags)
    played = collections.defaultdict(list)
    for line in out.read_text().splitlines():
        record = json.loads(line)
        if record.get("type") == "step":
            played[record["episode"]].append((record["action"], record["reward"]))
    return played


@pytest.mark.parametrize("world, expert", DEMONSTRATED, ids=[f"{w.name}-{e}" for w, e in DEMONSTRATED])
def test_demonstrations_play_what_the_cli_plays_legally_to_the_goal(world, expert, cli, tmp_path, task):
    kwargs = dict(world.kwargs, backend="grid", blocks=2 if world.view == "top" else 3, view=world.view)
    kwargs.pop("actions", None)
    demos = blockstack.demonstrations(3, expert=expert, obs="state", seed=5, **kwargs)
    rows = np.arange(len(demos["actions"]))
    assert demos["action_masks"][rows, demos["actions"]].all(), "every demonstrated action is legal"
    # The oracle of the original profile is the authors' greedy walker, which can get stuck.
    if not (expert == "oracle" and world.kwargs["profile"] == "original"):
        assert demos["terminations"].sum() == 3, "every episode reaches the goal"
    played = _cli_episodes(cli, tmp_path, expert, _cli_flags(world, task), 3, 5)
    for k in range(3):
        ours = demos["actions"][demos["episodes"] == k].tolist()
        assert ours == [a for a, _ in played[k]], (world.name, expert, k)


def _cli_flags(world, task) -> list:
    kw = world.kwargs
    flags = ["--backend", "grid", "--profile", kw.get("profile", "spec"), "--protocol", kw["protocol"]]
    if kw.get("pddl"):
        return flags + ["--pddl", task]
    flags += ["--view", world.view, "--blocks", "2" if world.view == "top" else "3"]
    return flags


@by_name([w for w in WORLDS if w.env_id != blockstack.GOAL_ENV_ID])
def test_the_cli_plays_what_the_python_expert_plays(world, task, cli, tmp_path):
    """Gripper actions: the same actions and rewards, step for step. Block moves: the CLI's
    fewest block moves carried out by the gripper (``exact-moves``) take the gripper steps
    and earn the reward the moves environment reports for its expert's moves."""
    agent = "exact-moves" if world.moves else "exact"
    episodes = _cli_episodes(cli, tmp_path, agent, _cli_flags(world, task), 2, 5)
    env = world.make(task)
    for k in range(2):
        env.reset(seed=blockstack.episode_seed(5, k))
        played = []
        while True:
            _, reward, terminated, truncated, info = env.step(env.expert_action())
            played.append((info.get("gripper_steps", 1), reward))
            if terminated or truncated:
                break
        cli_steps = episodes[k]
        assert sum(n for n, _ in played) == len(cli_steps), world.name
        if world.moves:
            assert len(played) == sum(a >= 5 for a, _ in cli_steps), "one pick (index 5 + block) a move"
            assert sum(r for _, r in played) == pytest.approx(sum(r for _, r in cli_steps))
        else:
            assert [r for _, r in played] == pytest.approx([r for _, r in cli_steps])


# Files -------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def fifo(tmp_path_factory) -> str:
    folder = tmp_path_factory.mktemp("fifo")
    path = folder / "input.pddl"
    os.mkfifo(path)
    return str(path)


#: Every Python reader of a file, as a call on the path ``p``.
#: A problem of the domain file a reader is given (``--domain``, ``domain=``).
DOMAIN_PROBLEM = os.path.join(os.path.dirname(os.path.abspath(__file__)), "fixtures", "problem-pickup.pddl")

PYTHON_READERS = {
    "read_pddl": "blockstack.read_pddl(p)",
    "solve_pddl(domain=)": f"blockstack.solve_pddl({DOMAIN_PROBLEM!r}, domain=p)",
    "BlocksWorld-v0(pddl=)": "blockstack.BlocksWorldEnv(pddl=p)",
    "read_recording": "blockstack.read_recording(p)",
    "load": "blockstack.load(p)",
    "to_minari": "blockstack.to_minari([p], 'conformance/never-v0')",
    "sweep config": "blockstack.sweep.read_config(p)",
}


@pytest.mark.parametrize("reader", sorted(PYTHON_READERS))
@pytest.mark.parametrize("special", ["fifo", "/dev/zero"])
def test_every_python_reader_refuses_a_fifo_or_a_device_at_once(reader, special, fifo, tmp_path):
    path = fifo if special == "fifo" else special
    # In a process of its own: a reader that opened a FIFO before looking would wait for a
    # writer forever, and /dev/zero would be read until memory ran out.
    script = (
        "import sys, blockstack, blockstack.sweep\n"
        "p = sys.argv[1]\n"
        "try:\n"
        f"    {PYTHON_READERS[reader]}\n"
        "except ValueError as e:\n"
        "    print(e)\n"
    )
    env = dict(os.environ, MINARI_DATASETS_PATH=str(tmp_path / "datasets"))
    run = subprocess.run([sys.executable, "-c", script, path], capture_output=True, text=True, timeout=60, env=env)
    assert run.returncode == 0, run.stderr
    assert "pipe or a device" in run.stdout, run.stdout


CLI_READERS = {
    "solve --pddl": lambda p: ["solve", "--pddl", p],
    "solve --domain": lambda p: ["solve", "--pddl", DOMAIN_PROBLEM, "--domain", p],
    "dqn --resume": lambda p: ["dqn", "--resume", p, "--out", "/tmp/never.safetensors"],
    "dqn --demos-file": lambda p: ["dqn", "--demos-file", p, "--out", "/tmp/never.safetensors", "--steps", "1"],
    "learn-from-demos": lambda p: ["learn-from-demos", p, "--model", p, "--out", "/tmp/never.safetensors"],
    "run --pddl": lambda p: ["run", "--pddl", p],
    "run --model": lambda p: ["run", "--agent", "q", "--model", p],
    "eval --model": lambda p: ["eval", "--model", p],
}


@pytest.mark.parametrize("reader", sorted(CLI_READERS))
@pytest.mark.parametrize("special", ["fifo", "/dev/zero"])
def test_every_cli_reader_refuses_a_fifo_or_a_device_at_once(reader, special, fifo, tmp_path):
    path = fifo if special == "fifo" else special
    binary = os.environ.get("BLOCKSTACK_BIN", str(pathlib_root() / "target" / "release" / "blockstack"))
    run = subprocess.run([binary, *CLI_READERS[reader](path)], capture_output=True, text=True, timeout=30)
    assert run.returncode == 2, run.stderr
    assert "pipe or a device" in run.stderr and run.stderr.count("\n") == 1, run.stderr


@pytest.mark.parametrize("special", ["fifo", "/dev/null"])
def test_a_plan_file_is_written_only_to_a_regular_file_or_a_new_path(special, fifo, cli, tmp_path):
    path = fifo if special == "fifo" else special
    binary = os.environ.get("BLOCKSTACK_BIN", str(pathlib_root() / "target" / "release" / "blockstack"))
    run = subprocess.run([binary, "solve", "--pddl", DOMAIN_PROBLEM, "--plan-file", path], capture_output=True,
                         text=True, timeout=30)
    assert run.returncode == 2 and "not a regular file" in run.stderr and run.stderr.count("\n") == 1, run.stderr
    with pytest.raises(ValueError, match="not a regular file"):
        blockstack.solve_pddl(DOMAIN_PROBLEM, plan_file=path)


@pytest.mark.parametrize("trainer", ["train", "dqn"])
def test_a_checkpoint_never_writes_over_a_trained_model(trainer, cli, tmp_path):
    # The file a run would destroy: a trained model of the other learner's kind too.
    model = tmp_path / "model.safetensors"
    cli("train", "--blocks", 2, "--goals", "0,1", "--games", 20, "--backend", "grid", "--out", model)
    before = model.read_bytes()
    flags = (["train", "--blocks", 2, "--goals", "0,1", "--games", 20, "--backend", "grid"] if trainer == "train"
             else ["dqn", "--preset", "dqn-planes", "--blocks", 2, "--steps", 10])
    binary = os.environ.get("BLOCKSTACK_BIN", str(pathlib_root() / "target" / "release" / "blockstack"))
    run = subprocess.run([binary, *map(str, flags), "--out", str(tmp_path / "new.safetensors"), "--checkpoint",
                          str(model)], capture_output=True, text=True, timeout=120)
    assert run.returncode != 0 and str(model) in run.stderr, run.stderr
    with pytest.raises(ValueError, match=str(model.name)):
        if trainer == "train":
            blockstack.train(blocks=2, goals="0,1", games=20, backend="grid", checkpoint=model)
        else:
            blockstack.train_dqn(preset="dqn-planes", blocks=2, steps=10, checkpoint=model)
    assert model.read_bytes() == before


def test_solve_all_refuses_a_fifo_among_its_tasks_and_goes_on(fifo, cli, tmp_path):
    folder = tmp_path / "tasks"
    folder.mkdir()
    (folder / "p01.pddl").write_text(TASK)
    os.symlink(fifo, folder / "p02.pddl")
    out = json.loads(cli("solve-all", "--tasks", folder, "--json"))
    rows = {row["task"]: row for row in out["tasks"]}
    assert rows["p01.pddl"]["actions"] is not None
    assert "pipe or a device" in rows["p02.pddl"]["error"]


def pathlib_root():
    import pathlib

    return pathlib.Path(__file__).resolve().parents[2]


# Every recording exports -------------------------------------------------------------------
#
# Each writer of recordings (a study's server, through the pilot; a person in the terminal,
# `demo`; a simulated demonstrator, `correct --record`) in each world it plays; the world's
# command-line flags, the condition keys of a study, and the world the dataset must recover.
# No writer plays a PDDL task (`run --pddl` writes trajectories, not recordings), so `pddl=`
# has no pair here.

#: name: (train and writer flags, study condition keys, recovered world keywords)
RECORDED = {
    "top spec free": ([], {"view": "top"}, {"view": "top", "protocol": "free", "start": "uniform"}),
    "top spec paper": (["--protocol", "paper"], None, {"view": "top", "protocol": "paper", "start": "uniform"}),
    "top original": (
        ["--profile", "original"],
        {"view": "top", "profile": "original"},
        {"view": "top", "protocol": "paper", "start": "paper", "reward": "paper-code"},
    ),
    "side spec free": (["--view", "side"], {"view": "side"}, {"view": "side", "protocol": "free", "start": "uniform"}),
}

#: The writers and the worlds each plays (`correct`'s simulated demonstrators plan the top
#: view only; a study's condition has a profile, not a protocol of its own).
WRITERS = {
    "correct": ("top spec free", "top spec paper", "top original"),
    "demo": ("top spec free", "top spec paper", "top original", "side spec free"),
    "serve": ("top spec free", "top original", "side spec free"),
}

EXPORTS = [(writer, world) for writer, worlds in WRITERS.items() for world in worlds]


def _model(cli, folder, world) -> str:
    model = folder / "model.safetensors"
    cli("train", "--games", "60", "--backend", "grid", "--out", model, *RECORDED[world][0])
    return str(model)


def _write_with_correct(cli, folder, world) -> list:
    record = folder / "correct.jsonl"
    model = _model(cli, folder, world)
    cli("correct", "--model", model, "--demonstrator", "1", "--demos", "2", "--out", folder / "c.safetensors",
        "--record", record, *RECORDED[world][0])
    return [record]


def _write_with_demo(cli, folder, world) -> list:
    import shutil
    import time

    if shutil.which("tmux") is None:
        pytest.skip("tmux is not installed (.ci/run installs it)")
    record = folder / "demo.jsonl"
    model = _model(cli, folder, world)
    flags = [f for f in RECORDED[world][0] if f not in ("--view", "side", "--profile", "original")]
    socket = str(folder / "tmux.sock")
    command = " ".join([_binary(), "demo", "--model", model, "--record", str(record), "--seed", "2", *flags])
    tmux = lambda *a: subprocess.run(["tmux", "-S", socket, *a], capture_output=True, text=True, timeout=30)  # noqa: E731
    assert tmux("new-session", "-d", "-s", "demo", "-x", "100", "-y", "40", command).returncode == 0
    try:
        deadline = time.monotonic() + 60
        # Faster, then a person's correction (a drop), then the agent again, then quit.
        tmux("send-keys", "-t", "demo", "+", "+", "+")
        while time.monotonic() < deadline and (not record.exists() or record.read_text().count('"type":"step"') < 3):
            time.sleep(0.1)
        tmux("send-keys", "-t", "demo", "d")
        count = record.read_text().count('"type":"step"')
        while time.monotonic() < deadline and record.read_text().count('"type":"step"') < count + 3:
            time.sleep(0.1)
        tmux("send-keys", "-t", "demo", "q")
        while time.monotonic() < deadline and tmux("has-session", "-t", "demo").returncode == 0:
            time.sleep(0.1)
    finally:
        tmux("kill-server")
    return [record]


def _write_with_serve(cli, folder, world) -> list:
    condition = dict(RECORDED[world][1], name="only", model="model.safetensors", goals="0,1,2", episodes=1)
    if world.startswith("side"):
        condition["goals"] = "0,1/2"
    _model(cli, folder, world)
    keys = "\n".join(f"{k} = {json.dumps(v)}" for k, v in condition.items())
    (folder / "study.toml").write_text(
        f'name = "conformance"\nseed = 3\nconsent = "You agree."\ninstructions = "Stack the blocks."\n'
        f'participant_ids = ["PROLIFIC_PID"]\ncompletion_code = "C0NF0R"\n[[condition]]\n{keys}\n'
    )
    cli("pilot", "--study", folder / "study.toml", "--participants", "1", "--record-dir", folder / "r", "--seed", "1")
    # The recordings, not the server's hidden ledger beside them.
    return sorted((folder / "r").glob("p*.jsonl"))


def _binary() -> str:
    return os.environ.get("BLOCKSTACK_BIN", str(pathlib_root() / "target" / "release" / "blockstack"))


@pytest.mark.parametrize("writer, world", EXPORTS, ids=[f"{w}-{x}" for w, x in EXPORTS])
def test_every_recording_exports_to_a_dataset_of_its_own_world(writer, world, cli, tmp_path, monkeypatch):
    pytest.importorskip("minari", reason="Minari is not installed (pip install 'minari[hdf5]')")
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path / "datasets"))
    write = {"correct": _write_with_correct, "demo": _write_with_demo, "serve": _write_with_serve}[writer]
    recordings = write(cli, tmp_path, world)
    dataset = blockstack.to_minari(recordings, f"conformance/{writer}-v0", obs="state", reference_episodes=2)
    assert dataset.total_episodes >= 1
    env = dataset.recover_environment().unwrapped
    kept = {k: getattr(env.world, k) for k in RECORDED[world][2]}
    assert kept == RECORDED[world][2], "the dataset's environment is the recordings' world"
    # Each episode replays in the recovered environment: the same rewards and ends.
    for episode in dataset.iterate_episodes():
        o = episode.observations
        held = int(o["held"][0])
        towers = collections.defaultdict(list)
        for block, tower in zip(o["goal"][0], o["goal_tower"][0]):
            if block >= 0:
                towers[int(tower)].append(str(int(block)))
        goal = "/".join(",".join(towers[t]) for t in sorted(towers))
        if len(towers) == 1 and len(towers[0]) < len(o["goal"][0]):
            goal += "/"  # one tower that leaves blocks free
        env.reset(options={"cells": [tuple(c) for c in o["blocks"][0]], "held": None if held < 0 else held,
                           "goal": goal})
        for action, reward, terminated in zip(episode.actions, episode.rewards, episode.terminations):
            _, r, t, _, info = env.step(int(action))
            assert r == pytest.approx(reward) and t == terminated and not info["illegal"], (writer, world)


# --- Planning a task: CLI = Python ---------------------------------------------------------

FIXTURES = os.path.join(os.path.dirname(os.path.abspath(__file__)), "fixtures")
#: The planners a PDDL task is planned by (``blockstack solve --pddl --solver``).
PDDL_SOLVERS = ("near-optimal", "optimal", "exact")
#: A task with no domain file, and each spelling's problem with its domain.
PDDL_TASKS = {
    "no-domain": None,
    "pickup": ("problem-pickup.pddl", "domain-pickup.pddl"),
    "pick-up": ("problem-pick-up.pddl", "domain-pick-up.pddl"),
}


@pytest.mark.parametrize("solver", PDDL_SOLVERS)
@pytest.mark.parametrize("spelling", sorted(PDDL_TASKS))
def test_solve_pddl_plans_what_the_cli_plans(solver, spelling, task, cli, tmp_path):
    files = PDDL_TASKS[spelling]
    problem = task if files is None else os.path.join(FIXTURES, files[0])
    domain = [] if files is None else ["--domain", os.path.join(FIXTURES, files[1])]
    ours = blockstack.solve_pddl(problem, solver=solver, domain=None if files is None else domain[1],
                                 plan_file=tmp_path / "python.plan")
    theirs = json.loads(cli("solve", "--pddl", problem, "--solver", solver, *domain, "--json",
                            "--plan-file", tmp_path / "cli.plan"))
    assert ours["plan"] == theirs["plan"] and ours["cost"] == theirs["actions"]
    assert ours["lower_bound"] == theirs["lower_bound"] <= ours["cost"]
    assert (ours["optimal"], ours["certificate"]) == (theirs["optimal"], theirs["certificate"])
    assert ours["text"] == cli("solve", "--pddl", problem, "--solver", solver, *domain)
    assert (tmp_path / "python.plan").read_text() == (tmp_path / "cli.plan").read_text() == ours["text"]
    if files is not None:
        # The plan speaks the domain's own action names.
        verbs = {a.strip("()").split()[0] for a in ours["plan"]}
        assert verbs <= ({"pick-up", "put-down", "stack", "unstack"} if spelling == "pick-up"
                         else {"pickup", "putdown", "stack", "unstack"})


@pytest.mark.parametrize("solver", PDDL_SOLVERS)
def test_solve_all_reports_what_the_cli_reports(solver, task, cli, tmp_path):
    folder = tmp_path / "tasks"
    cli("generate", "--blocks", 8, "--count", 2, "--seed", 5, "--shape", "ipc", "--out", folder)
    ours = blockstack.solve_all(folder, solver=solver)
    theirs = json.loads(cli("solve-all", "--tasks", folder, "--solver", solver, "--json"))
    strip = lambda rows: [{k: v for k, v in r.items() if k not in ("seconds", "cpu_seconds")} for r in rows]
    assert strip(ours["tasks"]) == strip(theirs["tasks"]) and len(ours["tasks"]) == 2
    assert {k: v for k, v in ours["overall"].items() if "second" not in k} == \
        {k: v for k, v in theirs["overall"].items() if "second" not in k}


# Default play ------------------------------------------------------------------------------
#
# One small model of each kind; the tabular one and the network trained with a reward that is
# not their profile's, so a front end that takes the profile's reward plays another game.

#: Each kind's epsilon when nothing says otherwise.
DEFAULT_EPSILON = {"q": 0.1, "dqn": 0.1, "relational": 0.0}

#: A goal of each kind's world (the relational policy's is the side view of 6 blocks).
DEFAULT_PLAY_GOAL = {"q": "0,1", "dqn": "0,1", "relational": "0,1,2/3,4,5"}


@pytest.fixture(scope="module")
def models(tmp_path_factory, cli) -> dict:
    folder = tmp_path_factory.mktemp("default-play")
    paths = {kind: str(folder / f"{kind}.safetensors") for kind in DEFAULT_EPSILON}
    cli("train", "--blocks", "2", "--games", "100", "--reward", "dense", "--backend", "grid", "--out", paths["q"])
    cli("dqn", "--preset", "dqn-planes", "--blocks", "2", "--steps", "60", "--reward", "dense", "--out", paths["dqn"])
    cli("dqn", "--preset", "general", "--blocks", "6", "--steps", "20", "--batch", "16", "--seed", "2", "--out", paths["relational"])
    return paths


@pytest.mark.parametrize("kind", sorted(DEFAULT_EPSILON))
def test_default_play_run_plays_the_models_epsilon_reward_and_world(kind, models, cli, tmp_path):
    model = blockstack.load(models[kind])
    assert model.kind == kind and model.default_epsilon == DEFAULT_EPSILON[kind]
    played = ["run", "--agent", kind, "--model", models[kind], "--episodes", "3", "--seed", "4", "--backend", "grid",
              "--goal", DEFAULT_PLAY_GOAL[kind], "--json"]
    default, named = tmp_path / "default.jsonl", tmp_path / "named.jsonl"
    by_default = json.loads(cli(*played, "--trajectory", default))
    by_name = json.loads(cli(*played, "--trajectory", named, "--epsilon", str(model.default_epsilon),
                             "--reward", model.world["reward"], "--view", model.world["view"]))
    assert by_default == by_name
    assert default.read_bytes() == named.read_bytes(), "the same steps and rewards"
    world = model.world
    assert (by_default["blocks"], by_default["protocol"], by_default["start"]) == (
        world["blocks"], world["protocol"], world["start"])


@pytest.mark.parametrize("kind", sorted(DEFAULT_EPSILON))
def test_default_play_eval_and_python_evaluate_play_the_models_epsilon(kind, models, cli):
    model = blockstack.load(models[kind])
    settings = {"episodes": 2, "seed": 3, "goals": DEFAULT_PLAY_GOAL[kind], "backend": "grid"}
    by_cli = json.loads(cli("eval", "--model", models[kind], "--json",
                            *[f"--{k}={v}" for k, v in settings.items()]))
    assert by_cli["epsilon"] == DEFAULT_EPSILON[kind]
    assert model.evaluate(**settings) == by_cli


@pytest.mark.parametrize("kind", sorted(DEFAULT_EPSILON))
def test_default_play_python_predict_plays_the_models_epsilon(kind, models):
    model = blockstack.load(models[kind])
    env = model.make_env(backend="grid")
    assert env.world.reward == model.world["reward"]
    obs, _ = env.reset(seed=5)
    model.reset(5)
    greedy = model.predict(obs)[0]
    chosen = {model.predict(obs, deterministic=False)[0] for _ in range(200)}
    # Greedy's epsilon is 0: the same move every time; 0.1 draws others among 200 calls.
    assert (chosen == {greedy}) == (DEFAULT_EPSILON[kind] == 0.0), chosen
