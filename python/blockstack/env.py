"""``blockstack/Stack-v0``: the Gymnasium environment over the Rust ``sim::Env``."""

from __future__ import annotations

import os
from typing import Any, Optional, Tuple

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from blockstack import _native
from blockstack._checks import cells_of, optional_whole
from blockstack._goal import Goal, goal_text
from blockstack.spaces import action_space, observation_space
from blockstack.world import world_of


def check_seed(seed: Any) -> Optional[int]:
    """``seed`` as an int in ``[0, 2**64)``, or ``None``; ``ValueError`` otherwise."""
    if seed is None:
        return None
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or not 0 <= int(seed) < 2**64:
        raise ValueError(f"a seed is an integer in [0, 2**64) or None, not {seed!r}")
    return int(seed)


#: The keys ``reset(options=...)`` reads; any other is refused (a typo must not be ignored).
RESET_OPTIONS = ("cells", "held", "goal")


def check_action(action: Any, blocks: int, count: Optional[int] = None) -> Any:
    """``action`` unchanged, or a ``ValueError`` for an integer outside the action range
    (the native side reads 64-bit integers only, and would call ``2**70`` "not an int").
    ``count`` is the number of actions when they are not the gripper's ``5 + blocks``."""
    if isinstance(action, (int, np.integer)) and not isinstance(action, bool):
        if count is not None:
            if not 0 <= int(action) < count:
                raise ValueError(f"block move {int(action)} is out of range: the moves are 0..{count}")
        elif not 0 <= int(action) < 5 + blocks:
            raise ValueError(
                f"action {int(action)} is out of range: with {blocks} blocks the actions are 0..{5 + blocks}"
            )
    return action


def reset_state(options: dict) -> Tuple[list, Optional[int], Goal]:
    """The ``(cells, held, goal)`` of ``reset(options=...)``, checked: known keys only,
    ``held`` and ``goal`` only with ``cells``, whole numbers in range."""
    if not isinstance(options, dict):
        raise ValueError(f"reset options are a dict with keys {', '.join(RESET_OPTIONS)}, not {options!r}")
    unknown = sorted(str(k) for k in options if k not in RESET_OPTIONS)
    if unknown:
        raise ValueError(f"unknown reset option(s) {', '.join(unknown)}: the options are {', '.join(RESET_OPTIONS)}")
    if "cells" not in options:
        raise ValueError(
            f"reset options {', '.join(sorted(options))} need \"cells\": a start state is every block's (x, y)"
        )
    cells = cells_of(options["cells"])
    held = optional_whole("held", options.get("held"), 0, 255)
    return cells, held, goal_text(options.get("goal"))


class StackEnv(gym.Env):
    """Blocks on a grid, picked, moved and dropped until they stand in the goal's order.

    Arguments (all keyword, as ``gymnasium.make("blockstack/Stack-v0", ...)`` passes them):
    the world keywords of :mod:`blockstack.world` (``blocks``, ``goal``, ``grid``,
    ``reward``, ``backend``, ``horizon`` / ``max_episode_steps``, ``profile``, ``protocol``,
    ``start``, ``view``), which every environment and :func:`blockstack.demonstrations`
    take alike, and:

    - ``obs``: ``planes``, ``role-planes``, ``frame``, ``paper-screen``, ``screen`` or ``state`` (see
      :mod:`blockstack.spaces`). ``planes`` does not carry the goal (``role-planes`` name
      blocks by their place in it, ``frame``, ``paper-screen`` and ``screen`` draw it), so with a drawn
      goal and ``planes`` use ``info["goal"]``.
    - ``actions``: ``gripper`` (the default, the ``5 + N`` actions) or, in the side view,
      ``moves``: block moves, ``x * (N + W) + d`` puts block ``x`` onto block ``d`` for
      ``d < N`` and onto the table at column ``d - N`` otherwise, each carried out as the
      gripper steps it takes (``info["gripper_steps"]``); ``info["action_mask"]`` marks the
      legal moves.
    - ``render_mode``: ``None``, ``rgb_array`` (the frame) or ``ansi`` (text).
    - ``strict``: what ``step`` does with an action the world's rules refuse (below).

    Every action of the action space is accepted, as Gymnasium's contract asks (random
    agents, ``gymnasium.utils.env_checker.check_env``, learners without masks). An action
    the world's rules refuse (under ``protocol="paper"`` or ``profile="original"``, the
    paper's world as its authors coded it: nothing held, picks only; holding, moves and drop
    only; from the side, a pick while holding or of a block under another; with
    ``actions="moves"``, a block moved onto itself or from under another) changes nothing:
    it still counts as a step towards the horizon, gets the world's reward for a step that
    changes nothing (under ``original`` the authors' code's -0.1 for a step that leaves the
    state as it was), and says so in ``info["illegal"] = True``. With ``strict=True`` it is
    a ``ValueError`` that changes nothing instead. ``info["action_mask"]`` says which
    actions are legal. In the side view (``view="side"``, ``blockstack/BlocksWorld-v0``:
    towers on a table, only a clear block can be picked, a released block falls) the legal
    actions are its own whatever the protocol. ``max_episode_steps`` is the horizon: an episode that
    has not reached the goal after this many steps is truncated by the Rust environment
    itself. (``gymnasium.make`` keeps its own ``max_episode_steps`` argument for Gymnasium's
    ``TimeLimit``: pass the horizon as ``horizon=`` there, or leave both at 1000.)

    Seeding: ``reset(seed=s)`` starts exactly where the Rust ``Env::reset(s)`` starts, so an
    episode here and ``blockstack run --trajectory`` with the same seeds and actions agree
    step for step; ``reset()`` continues the environment's generator. ``np_random`` is
    seeded with the same ``s`` for whatever else draws from it.

    ``info`` of ``reset`` and ``step``: ``action_mask`` (int8, 1 for every legal action,
    from the Rust ``ActionMask``; all ones in the ``spec`` world), ``blocked`` (a held block's move was
    stopped), ``illegal`` (the world's rules refused the action: nothing changed), ``pairs_in_place`` (goal pairs standing), ``goal`` and ``goal_tower`` (int64,
    as the ``state`` observation has them: :mod:`blockstack.spaces`).
    ``reset(options={"cells": [(x, y), ...], "held": i, "goal": "1,0,2"})`` starts from a
    given state instead (``held`` and ``goal`` only with ``cells``; any other key, or a
    start where the goal already holds, is a ``ValueError`` that changes nothing).

    Not picklable or copyable (the Rust world and its generator are not Python objects):
    make another with the same arguments and ``reset(options=...)`` it to ``state()``.
    """

    metadata = {"render_modes": ["rgb_array", "ansi"], "render_fps": 4}

    def __init__(
        self,
        obs: str = "planes",
        render_mode: Optional[str] = None,
        actions: str = "gripper",
        strict: bool = False,
        **world: Any,
    ):
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"cannot read render mode from {render_mode!r}: choose None, rgb_array or ansi")
        for name, value in (("obs", obs), ("actions", actions)):
            if not isinstance(value, str):
                raise ValueError(f"{name} is a name (text), not {value!r}")
        if not isinstance(strict, bool):
            raise ValueError(f"strict is True or False, not {strict!r}")
        #: The world this environment plays (:class:`blockstack.world.World`).
        self.world = world_of(world)
        self._native = _native.NativeEnv(self.world, obs, actions, strict)
        blocks, grid = self.world.blocks, self.world.grid
        self.render_mode = render_mode
        self.obs_kind = obs
        self._moves = actions == "moves"
        self.action_space = spaces.Discrete(self._native.action_count) if self._moves else action_space(blocks)
        self.observation_space = observation_space(obs, blocks, grid)
        self._mask = np.ones(self.action_space.n, dtype=np.int8)

    def reset(self, *, seed: Optional[int] = None, options: Optional[dict] = None):
        seed = check_seed(seed)
        if options:
            # Checked before anything changes: a refused reset leaves the episode as it was.
            cells, held, goal = reset_state(options)
            obs, info = self._native.reset_to(cells, held, goal)
            super().reset(seed=seed)
        else:
            super().reset(seed=seed)
            obs, info = self._native.reset(seed)
        self._mask = info["action_mask"]
        return obs, info

    def step(self, action):
        count = self._native.action_count if self._moves else None
        obs, reward, terminated, truncated, info = self._native.step(check_action(action, self._native.blocks, count))
        self._mask = info["action_mask"]
        return obs, reward, terminated, truncated, info

    def __reduce__(self):
        raise TypeError(
            "a StackEnv cannot be pickled or copied (its Rust world and generator are not "
            "Python objects): make another with the same arguments and reset(options=...) it to state()"
        )

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
        """The exact solver's next action, under the world's rules (its view and action
        protocol): the first of a shortest legal plan from here, in this environment's
        actions (with ``actions="moves"``, of the fewest block moves)."""
        return self._native.expert_action()

    def oracle_action(self) -> int:
        """The world's oracle's next action from here, under its rules (from the side, the
        near-optimal block-move planner's)."""
        return self._native.oracle_action()

    def optimal_steps(self) -> int:
        """The length of a shortest legal plan from here to the goal, in this environment's
        actions."""
        return self._native.optimal_steps()

    def state(self):
        """``(cells, held, goal)``: every block's ``(x, y)``, the held block or ``None``, the goal."""
        return self._native.state()


class BlocksWorldEnv(StackEnv):
    """``blockstack/BlocksWorld-v0``: :class:`StackEnv` in the side view, the classic Blocks
    World (``view="side"``): blocks stand on a table or on one another, only a clear block
    can be picked, and a released block falls to the top of the column below it (rapier's
    dynamics decide where on the ``physics`` backend). ``goal`` may name several towers,
    ``"0,1/2"``; ``actions`` is ``gripper`` or ``moves`` (block moves). The other arguments
    are :class:`StackEnv`'s.

    ``pddl``: a Blocks World problem in PDDL (a path; the file
    :func:`blockstack.read_pddl` reads), played as ``blockstack run --pddl`` plays it: the
    world's blocks, grid and goal are the task's (so ``blocks``, ``grid`` and ``goal`` are
    not given with it), and every ``reset()`` starts from the task's start state (its towers
    on columns 0, 1, ...) unless ``reset(options=...)`` gives another. A file refused, or a
    task whose start already meets its goal (an episode cannot begin over; its plan is
    empty), is a ``ValueError`` naming it.
    """

    def __init__(self, pddl: Any = None, **kwargs: Any):
        if "view" in kwargs:
            raise ValueError("BlocksWorld-v0 is the side view: use blockstack/Stack-v0 to choose a view")
        #: The task's start cells (``None`` without ``pddl``): where every ``reset()`` starts.
        self._task_start = None
        if pddl is not None:
            given = sorted(k for k in ("blocks", "grid", "goal") if k in kwargs)
            if given:
                raise ValueError(f"pddl= gives the world's blocks, grid and goal: leave out {', '.join(given)}")
            if not isinstance(pddl, (str, os.PathLike)):
                raise ValueError(f"pddl is the path of a PDDL problem file, not {pddl!r}")
            task = _native.pddl_task(os.fspath(pddl))
            kwargs.update(blocks=task["blocks"], goal=task["goal"])
            self._task_start = task["cells"]
        super().__init__(view="side", **kwargs)

    def reset(self, *, seed: Optional[int] = None, options: Optional[dict] = None):
        if self._task_start is not None and not options:
            options = {"cells": self._task_start}
        return super().reset(seed=seed, options=options)
