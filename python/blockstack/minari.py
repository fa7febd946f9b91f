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

Minari is an optional dependency (``pip install "minari[hdf5]"``).
"""

from __future__ import annotations

import inspect
import os
import warnings
from typing import Iterable, Optional, Union

import numpy as np

from blockstack import _native

PathLike = Union[str, os.PathLike]


def _world_key(e: dict) -> tuple:
    world = e["world"] or {}
    return (e["view"], tuple(e["grid"]), e["blocks"], world.get("reward"), world.get("protocol"), world.get("horizon"))


def _env_kwargs(e: dict, obs: str) -> dict:
    """The ``gymnasium.make`` keywords of the world episode ``e`` was played in."""
    world = e["world"] or {}
    kwargs = {
        "blocks": int(e["blocks"]),
        "grid": tuple(int(x) for x in e["grid"]),
        "obs": obs,
        "view": e["view"],
    }
    if world.get("reward") is not None:
        kwargs["reward"] = world["reward"]
    if world.get("protocol") is not None:
        kwargs["protocol"] = world["protocol"]
    if world.get("horizon") is not None:
        kwargs["max_episode_steps"] = int(world["horizon"])
    return kwargs


def _reference_scores(kwargs: dict, episodes: int, seed: int) -> tuple[float, float]:
    """Mean returns in the world of ``kwargs`` of uniformly random legal actions (the
    minimum) and of the exact solver's shortest plans (the maximum), on the same starts."""
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
    include_withdrawn: bool = False,
):
    """The recordings at ``paths`` (one path or several) as the Minari dataset
    ``dataset_id`` (``namespace/env/name-v0``, e.g. ``blockstack/stack/crowd-v0``), written
    under Minari's datasets folder (``MINARI_DATASETS_PATH``) and returned as a
    ``minari.MinariDataset`` (module docs).

    ``obs`` is the observation kind (``planes``, ``role-planes``, ``state``,
    ``paper-screen``, ...; :mod:`blockstack.spaces`): ``planes`` does not show the goal, so
    with several goals ``role-planes`` is what a learner needs. Every recording must be of
    one world (view, grid, block count, reward, protocol and horizon); a ``ValueError``
    says which differs. Observations are stored as they are: Minari's writer would
    JPEG-encode image-like arrays (``paper-screen``), so it is told not to.
    ``reference_episodes`` episodes from ``reference_episodes`` seeded starts (``seed``)
    give the reference scores. Withdrawn participants' recordings are left out (a warning
    names them) unless ``include_withdrawn=True`` (an audit).
    """
    try:
        import minari
        from minari.data_collector import EpisodeBuffer
    except ImportError as e:  # pragma: no cover - said to the user
        raise ImportError('to_minari needs Minari: pip install "minari[hdf5]"') from e
    import gymnasium as gym

    import blockstack

    if isinstance(paths, (str, bytes)) or hasattr(paths, "__fspath__"):
        paths = [paths]
    episodes = []
    withdrawn = []
    for path in paths:
        read = _native.recording_episodes(str(path), obs, include_withdrawn)
        if read["withdrawn"] and not include_withdrawn:
            withdrawn.append(os.fspath(path))
            continue
        if read["note"]:
            warnings.warn(read["note"], stacklevel=2)
        episodes.extend(read["episodes"])
    left_out = len(withdrawn)
    if withdrawn:
        warnings.warn(f"left out {left_out} withdrawn participants' recordings: {', '.join(withdrawn)}", stacklevel=2)
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
                f"episode {e['episode']} is of another world than the first "
                f"({_world_key(e)} against {_world_key(first)}): a dataset holds one world"
            )
    kwargs = _env_kwargs(first, obs)
    env_id = blockstack.ENV_ID
    spec = gym.spec(env_id)
    spec = gym.envs.registration.EnvSpec(
        id=spec.id,
        entry_point=spec.entry_point,
        max_episode_steps=None,
        kwargs=kwargs,
        vector_entry_point=spec.vector_entry_point,
    )
    env = blockstack.StackEnv(**kwargs)
    buffers = []
    for i, e in enumerate(episodes):
        observations = e["observations"]
        if isinstance(observations, dict):
            observations = {k: np.asarray(v) for k, v in observations.items()}
        # Minari keeps T + 1 infos (the reset's, then one per step): the first has no step.
        infos = {
            "person": np.concatenate([[0], e["person"].astype(np.int8)]).astype(np.int8),
            "t_ms": np.concatenate([[0], e["t_ms"]]).astype(np.int64),
        }
        buffers.append(
            EpisodeBuffer(
                id=i,
                observations=observations,
                actions=np.asarray(e["actions"], dtype=np.int64),
                rewards=np.asarray(e["rewards"], dtype=np.float64),
                terminations=np.asarray(e["terminations"], dtype=bool),
                truncations=np.asarray(e["truncations"], dtype=bool),
                infos=infos,
            )
        )
    low, high = _reference_scores(kwargs, reference_episodes, seed)
    people = sorted({(e["participant"] or {}).get("number") for e in episodes} - {None})
    conditions = sorted({(e["participant"] or {}).get("condition") for e in episodes} - {None})
    text = description or (
        f"{len(episodes)} episodes recorded by blockstack ({len(people)} participants"
        + (f", conditions {', '.join(conditions)}" if conditions else "")
        + f"; {left_out} withdrawn recordings left out) in the {first['view']} view, "
        f"{first['blocks']} blocks on a {first['grid'][0]}x{first['grid'][1]} grid. "
        "infos['person'] is 1 where the person chose the action; infos['t_ms'] the milliseconds "
        "since the episode's first view (-1: not timed)."
    )
    create = minari.create_dataset_from_buffers
    extra = {}
    if "jpeg_encoding" in inspect.signature(create).parameters:
        extra["jpeg_encoding"] = False
    return create(
        dataset_id=dataset_id,
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
        description=text,
        requirements=["blockstack"],
        **extra,
    )
