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
from typing import Optional, Tuple, Union

from blockstack import _native
from blockstack._checks import U32_MAX, fits_in_memory, memory_bytes, observation_bytes, whole
from blockstack._goal import Goal, goal_text

#: A lower bound on the bytes one step holds while the episodes are played: its two
#: observations as the Rust side keeps them, before they become arrays.
STEP_BYTES = 64


def demonstrations(
    episodes: int,
    expert: str = "exact",
    blocks: int = 3,
    seed: int = 0,
    obs: str = "planes",
    goal: Goal = None,
    grid: Tuple[int, int] = (7, 7),
    reward: Optional[str] = None,
    backend: str = "physics",
    max_episode_steps: int = 1000,
    profile: str = "spec",
    view: str = "top",
) -> dict:
    """``episodes`` episodes of an expert (``"exact"``: shortest plans; ``"oracle"``).

    ``view="side"`` plays the classic Blocks World: ``"exact"`` takes the fewest gripper
    steps, ``"oracle"`` carries out the near-optimal block-move planner's moves.

    Episode ``k`` starts from ``reset(episode_seed(seed, k))``: the start that
    ``blockstack run --seed SEED`` plays as its episode ``k``. ``grid`` is ``(width,
    height)`` or text such as ``"7x7"``. Every episode takes at least one step, so
    ``episodes`` whose arrays would need more than the machine's memory are refused up
    front (``ValueError``). Ctrl-C stops a long call with ``KeyboardInterrupt``.
    """
    episodes = whole("episodes", episodes)
    blocks = whole("blocks", blocks)
    seed = whole("seed", seed)
    steps = whole("max_episode_steps", max_episode_steps, 0, U32_MAX)
    grid = _native.grid_size(grid)
    per_step = 2 * observation_bytes(obs, blocks, grid) + (5 + blocks) + 27 + STEP_BYTES
    fits_in_memory(f"episodes={episodes}", episodes * per_step)
    return _native.demonstrations(
        episodes, expert, blocks, seed, obs, goal_text(goal), grid, reward, backend, steps, profile, view
    )


def read_recording(path: Union[str, os.PathLike], obs: str = "planes", profile: str = "spec") -> dict:
    """A recording the CLI wrote, as the arrays :func:`demonstrations` gives.

    Reads trajectory files (``blockstack run --trajectory FILE``) and demonstration
    recordings (``blockstack demo`` / ``correct --record FILE``); the lines tell which.
    Recordings do not name their world: ``action_masks`` follow ``profile``'s protocol.
    Every line is checked as ``blockstack dqn --demos-file`` checks it (the rules replayed,
    rewards and end flags that some reward model and termination rule give, one world per
    file): a file the CLI refuses raises ``ValueError`` with the CLI's message. A file
    whose arrays would need more than the machine's memory is refused, saying how large
    they would be, before they are made.
    """
    return _native.read_recording(os.fspath(path), obs, profile, memory_bytes())
