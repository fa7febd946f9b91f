"""Expert trajectories and the CLI's recordings as dicts of numpy arrays.

Both functions return the same keys, one row per step:

- ``observations``, ``next_observations``: ``(T, *obs shape)`` arrays (dicts of arrays for
  ``obs="state"``), the observation before and after each action;
- ``actions`` (int64), ``rewards`` (float64), ``terminations``, ``truncations`` (bool);
- ``episode_starts`` (bool, true at each episode's first step), ``episodes`` (int64);
- ``action_masks`` (int8, ``(T, 5 + N)``, the legal actions in each observation).

Ready for behaviour cloning (``observations`` -> ``actions``) or DQfD (add
``next_observations``, ``rewards`` and ``terminations`` to a replay buffer).
"""

from __future__ import annotations

import os
import warnings
from typing import Any, Optional, Union

from blockstack import _native
from blockstack._checks import fits_in_memory, memory_bytes, observation_bytes, whole
from blockstack.world import world_of

#: A lower bound on the bytes one step holds while the episodes are played: its two
#: observations as the Rust side keeps them, before they become arrays.
STEP_BYTES = 64


def demonstrations(
    episodes: int,
    expert: str = "exact",
    seed: int = 0,
    obs: str = "planes",
    **world: Any,
) -> dict:
    """``episodes`` episodes of an expert in the world the world keywords describe
    (:mod:`blockstack.world`, as every environment takes them), each as ``blockstack run
    --agent EXPERT`` plays it: ``"exact"`` (the fewest gripper steps, in either view) or
    ``"oracle"`` (the view's oracle), and in the side view (``view="side"``, the classic
    Blocks World) ``"exact-moves"`` (the fewest block moves, carried out by the gripper) or
    ``"near-optimal"`` (the near-optimal block-move planner, carried out).

    Episode ``k`` starts from ``reset(episode_seed(seed, k))``: the start that
    ``blockstack run --seed SEED`` plays as its episode ``k``. Every episode takes at least
    one step, so ``episodes`` whose arrays would need more than the machine's memory are
    refused up front (``ValueError``). Ctrl-C stops a long call with ``KeyboardInterrupt``.
    """
    episodes = whole("episodes", episodes)
    seed = whole("seed", seed)
    for name, value in (("expert", expert), ("obs", obs)):
        if not isinstance(value, str):
            raise ValueError(f"{name} is a name (text), not {value!r}")
    w = world_of(world)
    per_step = 2 * observation_bytes(obs, w.blocks, w.grid) + (5 + w.blocks) + 27 + STEP_BYTES
    fits_in_memory(f"episodes={episodes}", episodes * per_step)
    return _native.demonstrations(episodes, w, expert, seed, obs)


def read_recording(
    path: Union[str, os.PathLike],
    obs: str = "planes",
    profile: Optional[str] = None,
    *,
    include_withdrawn: bool = False,
) -> dict:
    """A recording the CLI wrote, as the arrays :func:`demonstrations` gives.

    Reads trajectory files (``blockstack run --trajectory FILE``) and demonstration
    recordings (``blockstack demo`` / ``correct --record FILE``); the lines tell which.
    With ``profile``, a recording of another action protocol than the profile's
    (``spec``: free, ``original``: the paper's) is refused, naming both, and
    ``action_masks`` follow the profile's protocol; without it they follow the protocol
    the recording names (free when it names none). Every line is checked as ``blockstack
    dqn --demos-file`` checks it (the rules replayed, rewards and end flags that some
    reward model and termination rule give, one world per file): a file the CLI refuses
    raises ``ValueError`` with the CLI's message. A withdrawn participant's recording is
    refused (``ValueError`` naming the withdrawal) unless ``include_withdrawn=True`` (an
    audit; a warning says so). A file whose arrays would need more than the machine's
    memory is refused, saying how large they would be, before they are made.
    """
    for name, value in (("obs", obs), ("profile", profile)):
        if value is not None and not isinstance(value, str):
            raise ValueError(f"{name} is a name (text), not {value!r}")
    if not isinstance(path, (str, os.PathLike)):
        raise ValueError(f"path is a file name (text or a path), not {path!r}")
    if not isinstance(include_withdrawn, bool):
        raise ValueError(f"include_withdrawn is True or False, not {include_withdrawn!r}")
    arrays, note = _native.read_recording(os.fspath(path), obs, profile, memory_bytes(), include_withdrawn)
    if note:
        warnings.warn(note, stacklevel=2)
    return arrays
