"""The observation and action spaces of a blockstack world."""

from __future__ import annotations

from typing import Tuple

import numpy as np
from gymnasium import spaces

from blockstack._native import OBS_KINDS, observation_shape

__all__ = ["OBS_KINDS", "action_space", "observation_space"]


def action_space(blocks: int) -> spaces.Discrete:
    """``5 + N`` actions: 0 up, 1 down, 2 left, 3 right, 4 drop, ``5 + i`` pick block ``i``."""
    return spaces.Discrete(5 + blocks)


def observation_space(obs: str, blocks: int, grid: Tuple[int, int]) -> spaces.Space:
    """The space of observation kind ``obs`` (one name per array, the Rust ``sim::ObsKind``).

    - ``planes``: ``Box`` of ``uint8`` 0/1, shape ``(W, H, N + 1)``: plane ``i < N`` marks
      block ``i``'s cell ``[x, y]`` (``y`` upward), plane ``N`` the held block's.
    - ``role-planes``: the same shape, plane ``p < N`` marking the block at place ``p`` of the
      goal (0 the bottom), so one policy serves every goal.
    - ``frame``: ``Box`` of ``uint8``, the rendered picture ``(height, width, 3)``, the goal
      drawn beside the grid (what ``render_mode="rgb_array"`` returns).
    - ``paper-screen``: ``Box`` of ``uint8``, ``(100, 100, 3)``: the paper's DQN input.
    - ``screen``: ``Box`` of ``uint8``, ``(4H, 4W, 3)``: the compact screen of the ``dqfd-screen``
      networks, every block in the colour of its place in the goal.
    - ``state``: ``Dict`` of ``blocks`` (``(N, 2)`` int64 cells), ``held`` (the held block's
      id, -1 for none), ``goal`` (``(N,)`` int64: the goal's blocks tower by tower, each
      bottom to top) and ``goal_tower`` (``(N,)`` int64: the tower of each entry of ``goal``,
      0 the first; all 0 for a goal of one tower). Entries past the blocks a goal of
      towers names (it may leave blocks free) are -1 in both.

    ``pixels`` (earlier releases) is refused: it meant ``frame`` here and ``paper-screen`` in
    the networks.
    """
    w, h = grid
    shape = observation_shape(obs, blocks, (w, h))
    if shape is not None:
        high = 1 if obs in ("planes", "role-planes") else 255
        return spaces.Box(0, high, shape=tuple(shape), dtype=np.uint8)
    high = np.tile(np.array([w - 1, h - 1], dtype=np.int64), (blocks, 1))
    return spaces.Dict(
        {
            "blocks": spaces.Box(np.zeros_like(high), high, dtype=np.int64),
            "held": spaces.Discrete(blocks + 1, start=-1),
            "goal": spaces.Box(-1, blocks - 1, shape=(blocks,), dtype=np.int64),
            "goal_tower": spaces.Box(-1, blocks - 1, shape=(blocks,), dtype=np.int64),
        }
    )
