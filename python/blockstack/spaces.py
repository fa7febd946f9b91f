"""The observation and action spaces of a blockstack world."""

from __future__ import annotations

from typing import Tuple

import numpy as np
from gymnasium import spaces

OBS_KINDS = ("planes", "state", "pixels")


def action_space(blocks: int) -> spaces.Discrete:
    """``5 + N`` actions: 0 up, 1 down, 2 left, 3 right, 4 drop, ``5 + i`` pick block ``i``."""
    return spaces.Discrete(5 + blocks)


def observation_space(obs: str, blocks: int, grid: Tuple[int, int], frame_shape: Tuple[int, int, int]) -> spaces.Space:
    """The space of observation kind ``obs``.

    - ``planes``: ``Box`` of ``uint8`` 0/1, shape ``(W, H, N + 1)``: plane ``i < N`` marks
      block ``i``'s cell ``[x, y]`` (``y`` upward), plane ``N`` the held block's.
    - ``state``: ``Dict`` of ``blocks`` (``(N, 2)`` int64 cells), ``held`` (the held block's
      id, -1 for none) and ``goal`` (``(N,)`` int64, bottom to top).
    - ``pixels``: ``Box`` of ``uint8``, the rendered frame ``(height, width, 3)``.
    """
    w, h = grid
    if obs == "planes":
        return spaces.Box(0, 1, shape=(w, h, blocks + 1), dtype=np.uint8)
    if obs == "pixels":
        return spaces.Box(0, 255, shape=frame_shape, dtype=np.uint8)
    if obs == "state":
        high = np.tile(np.array([w - 1, h - 1], dtype=np.int64), (blocks, 1))
        return spaces.Dict(
            {
                "blocks": spaces.Box(np.zeros_like(high), high, dtype=np.int64),
                "held": spaces.Discrete(blocks + 1, start=-1),
                "goal": spaces.Box(0, blocks - 1, shape=(blocks,), dtype=np.int64),
            }
        )
    raise ValueError(f"cannot read observation kind from {obs!r}: choose planes, state or pixels")
