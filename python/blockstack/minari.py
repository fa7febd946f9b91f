"""Recordings as a Minari dataset: what people taught, for offline learners.

``blockstack serve`` (a study's participants), ``blockstack demo`` (a person in the
terminal) and ``blockstack correct --record`` (a simulated demonstrator) write recordings;
:func:`to_minari` turns them into a dataset that ``minari.load_dataset`` opens and offline
learners (d3rlpy, TorchRL, ...) read::

    import blockstack
    dataset = blockstack.to_minari(["recordings/p0000-top.jsonl"], "blockstack/stack/crowd-v0")
    env = dataset.recover_environment()        # blockstack/Stack-v0, the recordings' world

One Minari episode per recorded episode with a step: its observations (T + 1), actions,
rewards, terminations and truncations (an episode a crash or a mode switch cut short ends
truncated), and ``infos`` with, per step, ``person`` (1 if the person chose the action, 0
if the agent did) and ``t_ms`` (milliseconds since the episode's first view, -1 when the
recording kept no time). Recordings of participants who withdrew are left out. The
reference scores are the mean returns of random play and of the exact solver's shortest
plans in the same world.

The dataset id is checked before anything is written: it must name a folder inside Minari's
datasets folder (``..`` and absolute paths are refused), and the export is made in a hidden
folder beside the datasets and moved into place only once it is complete, so an export that
fails (a bad recording, Minari refusing a space, a crash) leaves nothing behind and the id
stays free.

Minari is an optional dependency (``pip install "minari[hdf5]"``).
"""

from __future__ import annotations

import inspect
import os
import re
import shutil
import tempfile
import warnings
from pathlib import Path
from typing import Iterable, List, Optional, Union

import numpy as np

from blockstack import _native

PathLike = Union[str, os.PathLike]

#: A dataset id blockstack writes: ``namespace/.../name-vN``, each part letters, digits,
#: ``_``, ``-`` or ``.``, none of them ``.`` or ``..``: it names a folder inside Minari's
#: datasets folder and nothing outside it.
_DATASET_ID = re.compile(r"[A-Za-z0-9_.-]+(/[A-Za-z0-9_.-]+)*-v[0-9]+")

#: The world keywords a recording's ``world`` carries, as ``gymnasium.make`` names them.
_WORLD_KEYWORDS = {"horizon": "max_episode_steps"}


def _world_key(e: dict) -> tuple:
    world = e["world"] or {}
    return (e["view"], tuple(e["grid"]), e["blocks"], tuple(sorted((k, str(v)) for k, v in world.items())))


def _env_kwargs(e: dict, obs: str) -> dict:
    """The ``gymnasium.make`` keywords of the world episode ``e`` was played in."""
    kwargs = {
        "blocks": int(e["blocks"]),
        "grid": tuple(int(x) for x in e["grid"]),
        "obs": obs,
        "view": e["view"],
    }
    for key, value in (e["world"] or {}).items():
        if value is not None:
            kwargs[_WORLD_KEYWORDS.get(key, key)] = int(value) if key == "horizon" else value
    return kwargs


def _reference_scores(kwargs: dict, episodes: int, seed: int) -> tuple[float, float]:
    """Mean returns in the world of ``kwargs`` of uniformly random legal actions (the
    minimum) and of the expert's shortest plans under the world's protocol (the maximum),
    on the same starts."""
    import blockstack

    env = blockstack.StackEnv(**kwargs)
    rng = np.random.default_rng(seed)
    low, high = [], []
    for k in range(episodes):
        start_seed = blockstack.episode_seed(seed, k)
        for expert, out in ((False, low), (True, high)):
            _, info = env.reset(seed=start_seed)
            total, done = 0.0, False
            while not done:
                if expert:
                    action = env.expert_action()
                else:
                    legal = np.flatnonzero(info["action_mask"])
                    action = int(rng.choice(legal))
                _, reward, terminated, truncated, info = env.step(action)
                total += reward
                done = terminated or truncated
            out.append(total)
    return float(np.mean(low)), float(np.mean(high))


def check_dataset_id(dataset_id: str) -> Path:
    """The folder ``dataset_id`` names under Minari's datasets folder; a ``ValueError``,
    before anything is written, for an id that is malformed (no ``-vN`` version), that would
    leave that folder (``..``, an absolute path) or that is taken."""
    from minari.dataset.minari_dataset import parse_dataset_id
    from minari.storage import get_dataset_path

    if not isinstance(dataset_id, str):
        raise ValueError(f"a dataset id is text, namespace/name-v0, not {dataset_id!r}")
    parts = dataset_id.split("/")
    if not _DATASET_ID.fullmatch(dataset_id) or any(p in (".", "..") for p in parts):
        raise ValueError(
            f"dataset id {dataset_id!r} is not one blockstack writes: give namespace/name-vN "
            "(e.g. blockstack/stack/crowd-v0), each part letters, digits, _, - or ., none of them . or .."
        )
    parse_dataset_id(dataset_id)
    folder = Path(get_dataset_path(dataset_id))
    if folder.exists():
        raise ValueError(f"a Minari dataset with id {dataset_id} exists already ({folder}): choose another name or version")
    return folder


def _create_in_place(dataset_id: str, folder: Path, **create_args):
    """Minari's ``create_dataset_from_buffers`` made in a hidden folder beside the datasets
    (Minari lists no hidden folder), then moved to ``folder``: complete, or not there."""
    import minari
    from minari.namespace import NAMESPACE_METADATA_FILENAME
    from minari.storage import get_dataset_path

    root = Path(get_dataset_path())
    staging = Path(tempfile.mkdtemp(prefix=".blockstack-export-", dir=root))
    previous = os.environ.get("MINARI_DATASETS_PATH")
    try:
        os.environ["MINARI_DATASETS_PATH"] = str(staging)
        minari.create_dataset_from_buffers(dataset_id=dataset_id, **create_args)
        os.environ.pop("MINARI_DATASETS_PATH")
        if previous is not None:
            os.environ["MINARI_DATASETS_PATH"] = previous
        # The namespaces Minari made for the id, where the datasets folder lacks them.
        parts = dataset_id.split("/")[:-1]
        for depth in range(1, len(parts) + 1):
            made = staging.joinpath(*parts[:depth], NAMESPACE_METADATA_FILENAME)
            there = root.joinpath(*parts[:depth], NAMESPACE_METADATA_FILENAME)
            if made.exists() and not there.exists():
                there.parent.mkdir(parents=True, exist_ok=True)
                shutil.copyfile(made, there)
        folder.parent.mkdir(parents=True, exist_ok=True)
        os.rename(staging.joinpath(*dataset_id.split("/")), folder)
    finally:
        if previous is None:
            os.environ.pop("MINARI_DATASETS_PATH", None)
        else:
            os.environ["MINARI_DATASETS_PATH"] = previous
        shutil.rmtree(staging, ignore_errors=True)
    return minari.load_dataset(dataset_id)


def _episodes(paths: List[PathLike], obs: str, world: Optional[dict], include_withdrawn: bool) -> tuple[list, int]:
    """Every episode with a step of the recordings at ``paths``, each with its ``path``, and
    how many recordings were left out as withdrawn (a warning names them; only withdrawn
    ones: a ``ValueError`` naming the withdrawal), unless ``include_withdrawn``; a
    ``ValueError`` for recordings of several worlds, or of an older version that recorded
    no world when ``world`` is not given."""
    episodes = []
    withdrawn = []
    for path in paths:
        read = _native.recording_episodes(str(path), obs, include_withdrawn)
        if read["withdrawn"] and not include_withdrawn:
            withdrawn.append(os.fspath(path))
            continue
        if read["note"]:
            warnings.warn(read["note"], stacklevel=3)
        for e in read["episodes"]:
            e["path"] = str(path)
            if e["world"] is None:
                if world is None:
                    raise ValueError(
                        f"{path} is a recording of version 1 or 2, which does not say its world's reward, "
                        "protocol and horizon: pass them as world={'reward': ..., 'protocol': ..., 'horizon': ...}"
                    )
                e["world"] = dict(world)
        episodes.extend(read["episodes"])
    left_out = len(withdrawn)
    if withdrawn:
        warnings.warn(f"left out {left_out} withdrawn participants' recordings: {', '.join(withdrawn)}", stacklevel=3)
    if not episodes and withdrawn:
        raise ValueError(
            f"every recording given is a withdrawn participant's ({', '.join(withdrawn)}): left out of every "
            "analysis; include_withdrawn=True reads them for an audit"
        )
    if not episodes:
        raise ValueError("the recordings hold no episode with a step")
    first = episodes[0]
    for e in episodes[1:]:
        if _world_key(e) != _world_key(first):
            raise ValueError(
                f"{e['path']} (its episode {e['episode']}) is of another world than {first['path']} "
                f"({_world_key(e)} against {_world_key(first)}): a dataset holds one world"
            )
    return episodes, left_out


def _buffer(i: int, e: dict):
    """Episode ``e`` as Minari's ``EpisodeBuffer`` number ``i``."""
    from minari.data_collector import EpisodeBuffer

    observations = e["observations"]
    if isinstance(observations, dict):
        observations = {k: np.asarray(v) for k, v in observations.items()}
    # Minari keeps T + 1 infos (the reset's, then one per step): the first has no step.
    infos = {
        "person": np.concatenate([[0], e["person"].astype(np.int8)]).astype(np.int8),
        "t_ms": np.concatenate([[0], e["t_ms"]]).astype(np.int64),
    }
    return EpisodeBuffer(
        id=i,
        observations=observations,
        actions=np.asarray(e["actions"], dtype=np.int64),
        rewards=np.asarray(e["rewards"], dtype=np.float64),
        terminations=np.asarray(e["terminations"], dtype=bool),
        truncations=np.asarray(e["truncations"], dtype=bool),
        infos=infos,
    )


def _description(episodes: list, left_out: int) -> str:
    first = episodes[0]
    people = sorted({(e["participant"] or {}).get("number") for e in episodes} - {None})
    conditions = sorted({(e["participant"] or {}).get("condition") for e in episodes} - {None})
    return (
        f"{len(episodes)} episodes recorded by blockstack ({len(people)} participants"
        + (f", conditions {', '.join(conditions)}" if conditions else "")
        + f"; {left_out} withdrawn recordings left out) in the {first['view']} view, "
        f"{first['blocks']} blocks on a {first['grid'][0]}x{first['grid'][1]} grid. "
        "infos['person'] is 1 where the person chose the action; infos['t_ms'] the milliseconds "
        "since the episode's first view (-1: not timed)."
    )


def to_minari(
    paths: Union[PathLike, Iterable[PathLike]],
    dataset_id: str,
    obs: str = "planes",
    *,
    author: Optional[str] = None,
    author_email: Optional[str] = None,
    description: Optional[str] = None,
    code_permalink: Optional[str] = None,
    reference_episodes: int = 100,
    seed: int = 0,
    world: Optional[dict] = None,
    include_withdrawn: bool = False,
):
    """The recordings at ``paths`` (one path or several) as the Minari dataset
    ``dataset_id`` (``namespace/env/name-v0``, e.g. ``blockstack/stack/crowd-v0``), written
    under Minari's datasets folder (``MINARI_DATASETS_PATH``) and returned as a
    ``minari.MinariDataset`` (module docs).

    ``obs`` is the observation kind (``planes``, ``role-planes``, ``state``,
    ``paper-screen``, ...; :mod:`blockstack.spaces`): ``planes`` does not show the goal, so
    with several goals ``role-planes`` is what a learner needs. Every recording must be of
    one world (view, grid, block count and the world its session line records); a
    ``ValueError`` names the file that differs. A recording older than version 3 does not
    record its world: ``world`` gives it (``{"reward": ..., "protocol": ..., "horizon":
    ...}``). Observations are stored as they are: Minari's writer would JPEG-encode
    image-like arrays (``paper-screen``), so it is told not to. ``reference_episodes``
    episodes from ``reference_episodes`` seeded starts (``seed``) give the reference scores.
    Withdrawn participants' recordings are left out (a warning names them) unless
    ``include_withdrawn=True`` (an audit).
    """
    try:
        import minari
    except ImportError as e:  # pragma: no cover - said to the user
        raise ImportError('to_minari needs Minari: pip install "minari[hdf5]"') from e
    import gymnasium as gym

    import blockstack

    folder = check_dataset_id(dataset_id)
    if isinstance(paths, (str, bytes)) or hasattr(paths, "__fspath__"):
        paths = [paths]
    episodes, left_out = _episodes(list(paths), obs, world, include_withdrawn)
    kwargs = _env_kwargs(episodes[0], obs)
    registered = gym.spec(blockstack.ENV_ID)
    spec = gym.envs.registration.EnvSpec(
        id=registered.id,
        entry_point=registered.entry_point,
        max_episode_steps=None,
        kwargs=kwargs,
        vector_entry_point=registered.vector_entry_point,
    )
    env = blockstack.StackEnv(**kwargs)
    buffers = [_buffer(i, e) for i, e in enumerate(episodes)]
    low, high = _reference_scores(kwargs, reference_episodes, seed)
    extra = {}
    if "jpeg_encoding" in inspect.signature(minari.create_dataset_from_buffers).parameters:
        extra["jpeg_encoding"] = False
    return _create_in_place(
        dataset_id,
        folder,
        buffer=buffers,
        env=spec,
        eval_env=spec,
        algorithm_name="people (blockstack serve / demo) and simulated demonstrators (blockstack correct)",
        author=author or "blockstack",
        author_email=author_email,
        code_permalink=code_permalink,
        action_space=env.action_space,
        observation_space=env.observation_space,
        ref_min_score=low,
        ref_max_score=high,
        description=description or _description(episodes, left_out),
        requirements=["blockstack"],
        **extra,
    )
