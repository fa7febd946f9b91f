"""``blockstack/Stack-v0``: the Gymnasium environment over the Rust ``sim::Env``."""

from __future__ import annotations

from typing import Any, Optional, Tuple

import gymnasium as gym
import numpy as np

from blockstack import _native
from blockstack._goal import Goal, goal_text
from blockstack.spaces import action_space, observation_space


def check_seed(seed: Any) -> Optional[int]:
    """``seed`` as an int in ``[0, 2**64)``, or ``None``; ``ValueError`` otherwise."""
    if seed is None:
        return None
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or not 0 <= int(seed) < 2**64:
        raise ValueError(f"a seed is an integer in [0, 2**64) or None, not {seed!r}")
    return int(seed)


class StackEnv(gym.Env):
    """Blocks on a grid, picked, moved and dropped until they stand in the goal's order.

    Arguments (all keyword, as ``gymnasium.make("blockstack/Stack-v0", ...)`` passes them):

    - ``blocks``: number of blocks ``N`` (2 to 16; default 3).
    - ``goal``: the stack bottom to top (``"1,0,2"`` or ``[1, 0, 2]``); ``None`` draws one
      each episode. ``planes`` does not carry the goal (``role-planes`` name blocks by
      their place in it, ``frame`` and ``paper-screen`` draw it), so with a drawn goal and
      ``planes`` use ``info["goal"]``.
    - ``grid``: ``(width, height)``, default ``(7, 7)``.
    - ``reward``: ``sparse`` (+10 at the goal), ``dense``, ``paper`` or ``step-cost``;
      ``None`` (the default) takes the profile's (``sparse`` in ``spec``).
    - ``backend``: ``physics`` (rapier2d) or ``grid`` (the occupancy model); same rules.
    - ``obs``: ``planes``, ``role-planes``, ``frame``, ``paper-screen`` or ``state`` (see
      :mod:`blockstack.spaces`).
    - ``profile``: ``spec`` (the world of the SPEC: every action legal) or ``original`` (the
      paper's world as its authors coded it: their action protocol, nothing held: picks
      only, holding: moves and drop only; their start rule; the ``paper-code`` reward).
      An illegal action is a ``ValueError`` that changes nothing; ``info["action_mask"]``
      says which are legal. (``gymnasium.utils.env_checker.check_env`` steps random
      actions, so it passes in ``spec`` only.)
    - ``protocol`` (``free`` or ``paper``) and ``start`` (``uniform`` or ``paper``): one rule
      of the profile each, set otherwise; ``None`` (the default) keeps the profile's.
    - ``render_mode``: ``None``, ``rgb_array`` (the frame) or ``ansi`` (text).
    - ``max_episode_steps``: the horizon: an episode that has not reached the goal after
      this many steps is truncated, by the Rust environment itself. (``gymnasium.make``
      keeps its own ``max_episode_steps`` argument for Gymnasium's ``TimeLimit``: pass the
      horizon as ``horizon=`` there, or leave both at 1000.)

    Seeding: ``reset(seed=s)`` starts exactly where the Rust ``Env::reset(s)`` starts, so an
    episode here and ``blockstack run --trajectory`` with the same seeds and actions agree
    step for step; ``reset()`` continues the environment's generator. ``np_random`` is
    seeded with the same ``s`` for whatever else draws from it.

    ``info`` of ``reset`` and ``step``: ``action_mask`` (int8, 1 for every legal action,
    from the Rust ``ActionMask``; all ones in the ``spec`` world), ``blocked`` (a held block's move was
    stopped), ``pairs_in_place`` (goal pairs standing), ``goal`` (int64, bottom to top).
    ``reset(options={"cells": [(x, y), ...], "held": i, "goal": "1,0,2"})`` starts from a
    given state instead.
    """

    metadata = {"render_modes": ["rgb_array", "ansi"], "render_fps": 4}

    def __init__(
        self,
        blocks: int = 3,
        goal: Goal = None,
        grid: Tuple[int, int] = (7, 7),
        reward: Optional[str] = None,
        backend: str = "physics",
        obs: str = "planes",
        profile: str = "spec",
        render_mode: Optional[str] = None,
        max_episode_steps: int = 1000,
        horizon: Optional[int] = None,
        protocol: Optional[str] = None,
        start: Optional[str] = None,
    ):
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"cannot read render mode from {render_mode!r}: choose None, rgb_array or ansi")
        steps = max_episode_steps if horizon is None else horizon
        self._native = _native.NativeEnv(
            blocks, goal_text(goal), tuple(grid), reward, backend, steps, profile, obs, protocol, start
        )
        self.render_mode = render_mode
        self.obs_kind = obs
        self.action_space = action_space(blocks)
        self.observation_space = observation_space(obs, blocks, tuple(grid))
        self._mask = np.ones(self.action_space.n, dtype=np.int8)

    def reset(self, *, seed: Optional[int] = None, options: Optional[dict] = None):
        seed = check_seed(seed)
        super().reset(seed=seed)
        if options and "cells" in options:
            obs, info = self._native.reset_to(
                [tuple(c) for c in options["cells"]], options.get("held"), options.get("goal")
            )
        else:
            obs, info = self._native.reset(seed)
        self._mask = info["action_mask"]
        return obs, info

    def step(self, action):
        obs, reward, terminated, truncated, info = self._native.step(action)
        self._mask = info["action_mask"]
        return obs, reward, terminated, truncated, info

    def render(self):
        if self.render_mode == "rgb_array":
            return self._native.render_rgb()
        if self.render_mode == "ansi":
            return self._native.render_ansi()
        return None

    def action_masks(self) -> np.ndarray:
        """The legal actions now, as booleans (what sb3-contrib's MaskablePPO asks for)."""
        return self._mask.astype(bool)

    def expert_action(self) -> int:
        """The exact solver's next action: the first of a shortest plan from here."""
        return self._native.expert_action()

    def oracle_action(self) -> int:
        """The oracle's next action from here."""
        return self._native.oracle_action()

    def optimal_steps(self) -> int:
        """The length of a shortest plan from here to the goal."""
        return self._native.optimal_steps()

    def state(self):
        """``(cells, held, goal)``: every block's ``(x, y)``, the held block or ``None``, the goal."""
        return self._native.state()
