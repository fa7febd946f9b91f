"""Trained models: ``blockstack.load(path)`` reads a model file of any kind (a tabular
Q-agent from ``blockstack train``, a network from ``blockstack dqn``, a relational policy of
block moves from ``blockstack dqn --preset general``) and plays it with Stable-Baselines3's
conventions::

    model = blockstack.load("role.safetensors")
    env = model.make_env()                      # the world it was trained in, obs="state"
    obs, info = env.reset(seed=7)
    model.reset(7)                              # break ties as `blockstack run` would
    action, _ = model.predict(obs, deterministic=True)
    report = model.evaluate(episodes=100, seed=2)   # what `blockstack eval --json` prints

``predict`` reads the ``state`` observation (a dict of ``blocks``, ``held``, ``goal`` and
``goal_tower``),
which holds everything every kind of model needs; ``make_env`` makes environments that
show it; a network on pixels also plays on its own picture (``make_env(obs=model.picture)``,
``predict(obs, info=info)``). A relational policy plays the side view at any number of blocks, a block move at a
time: its ``make_env`` takes block moves (``actions="moves"``), and ``predict`` returns a
block move's index there (pass ``grid=`` for an environment on another grid than the
model's world's)::

    model = blockstack.load("general.safetensors")
    env = model.make_env(blocks=6)
    obs, info = env.reset(seed=7)
    move, _ = model.predict(obs)                # a block move of the env's action space
"""

from __future__ import annotations

import json
import os
from typing import Any, Optional, Tuple, Union

import numpy as np

from blockstack import _native
from blockstack._checks import U32_MAX, whole, whole_numbers
from blockstack.env import StackEnv


class Model:
    """A trained model read from a file (:func:`load`)."""

    def __init__(self, path: Union[str, os.PathLike]):
        if not isinstance(path, (str, os.PathLike)):
            raise ValueError(f"path is a file name (text or a path), not {path!r}")
        self._native = _native.NativeModel(os.fspath(path))
        self.path = os.fspath(path)

    @property
    def kind(self) -> str:
        """``q`` (a tabular Q-agent), ``dqn`` (a network) or ``relational`` (a relational
        policy of block moves)."""
        return self._native.kind

    @property
    def default_epsilon(self) -> float:
        """The probability of a random legal action the model plays with unless told
        otherwise, as ``blockstack run`` and ``blockstack eval`` play it: its profile's test
        policy (0.1) for a tabular model or a network, 0 for a relational policy."""
        return self._native.default_epsilon

    @property
    def name(self) -> str:
        """The model's name in reports."""
        return self._native.name

    @property
    def world(self) -> dict:
        """The world it was trained in, as :class:`blockstack.StackEnv` keyword arguments."""
        return self._native.world()

    @property
    def picture(self) -> Optional[str]:
        """The environment observation a network on pixels reads (``paper-screen`` or
        ``screen``), which :meth:`predict` takes with the step's info; ``None`` for a model
        that reads planes or a table."""
        return self._native.picture

    def make_env(self, **overrides: Any) -> StackEnv:
        """A Gymnasium environment of the world the model was trained in, showing the
        ``state`` observation that :meth:`predict` reads; ``overrides`` change any keyword
        argument of :class:`blockstack.StackEnv` (``goal``, ``backend``, ``render_mode``...).
        A world the model cannot play (another grid, number of blocks or view) is a
        ``ValueError``, as ``blockstack run --model`` refuses it."""
        kwargs = dict(self.world, obs="state")
        if self.kind == "relational":
            kwargs["actions"] = "moves"
        kwargs.update(overrides)
        env = StackEnv(**kwargs)
        self._native.check_world(env.world)
        return env

    def reset(self, seed: int) -> None:
        """Starts the policy's generator for an episode reset with ``seed``, as ``blockstack
        run`` does, so that ties are broken as the CLI breaks them."""
        self._native.reset(whole("seed", seed))

    def predict(
        self,
        observation: Union[dict, np.ndarray],
        state: Any = None,
        episode_start: Optional[np.ndarray] = None,
        deterministic: bool = True,
        grid: Optional[Tuple[int, int]] = None,
        info: Optional[dict] = None,
    ) -> Tuple[int, None]:
        """``(action, None)``: the greedy action, or with ``deterministic=False`` the model's
        default play, as ``blockstack run`` plays it: a random legal action with probability
        :attr:`default_epsilon` (0.1 for a tabular model or a network, the paper's test policy;
        a relational policy plays greedy). ``state`` and
        ``episode_start`` are Stable-Baselines3's arguments for recurrent policies, unused
        here.

        ``observation`` is the ``state`` observation (a dict of ``blocks``, ``held``, ``goal``
        and ``goal_tower``), which every kind of model plays as ``blockstack run`` does. For
        a relational policy the action is a block move of an environment with
        ``actions="moves"`` on ``grid`` (default: the model's world's grid). For a network on
        pixels ``observation`` may be the picture it reads (the environment's
        ``paper-screen``, or ``screen`` for a ``dqfd-screen`` network) with the step's ``info``
        (its ``goal``, ``goal_tower`` and ``action_mask``): greedy among the legal actions,
        since the no-op mask ``blockstack run`` adds needs the state."""
        epsilon = 0.0 if deterministic else self.default_epsilon
        if isinstance(observation, np.ndarray) and self.picture is not None:
            if info is None or not {"goal", "action_mask"} <= set(info):
                raise ValueError(
                    "predict on a picture needs the step's info (its goal and action_mask): "
                    "model.predict(obs, info=info)"
                )
            goal = [int(b) for b in np.asarray(info["goal"])]
            towers = [int(t) for t in np.asarray(info.get("goal_tower", [0] * len(goal)))]
            mask = [int(m) for m in np.asarray(info["action_mask"])]
            picture = np.ascontiguousarray(observation, dtype=np.uint8)
            return self._native.act_on_picture(picture, goal, towers, mask, epsilon), None
        if not isinstance(observation, dict) or not {"blocks", "held", "goal"} <= set(observation):
            also = f", or the {self.picture} observation with the step's info" if self.picture else ""
            raise ValueError(
                f"predict reads the state observation (a dict of blocks, held and goal){also}: make the "
                "environment with obs='state', as model.make_env() does"
            )
        blocks = _whole_array("blocks", observation["blocks"])
        if blocks.ndim != 2 or blocks.shape[1:] != (2,):
            raise ValueError(f"observation['blocks'] is every block's (x, y), shape (N, 2), not {blocks.shape}")
        held = _whole_array("held", observation["held"])
        if held.ndim != 0:
            raise ValueError(f"observation['held'] is one block id (or -1), not an array of shape {held.shape}")
        goal = _whole_array("goal", observation["goal"])
        # Without ``goal_tower`` (observations of releases before it) the goal is one tower.
        towers = _whole_array("goal_tower", observation.get("goal_tower", np.zeros(len(goal), dtype=np.int64)))
        if blocks.size and not (0 <= blocks.min() and blocks.max() <= 255):
            raise ValueError("observation['blocks'] holds a cell outside any grid (0..255)")
        if not -1 <= int(held) <= 255:
            raise ValueError(f"observation['held'] is a block id or -1, not {int(held)}")
        cells = [(int(x), int(y)) for x, y in blocks]
        held = int(held)
        goal = [int(b) for b in goal]
        towers = [int(t) for t in towers]
        if self.kind == "relational":
            size = tuple(grid) if grid is not None else tuple(self.world["grid"])
            move = self._native.act_move(cells, None if held < 0 else held, goal, towers, size, epsilon)
            return move, None
        action = self._native.act(cells, None if held < 0 else held, goal, towers, epsilon)
        return action, None

    def evaluate(
        self,
        episodes: int = 500,
        seed: int = 2,
        goals: Optional[str] = None,
        epsilon: Optional[float] = None,
        backend: str = "physics",
        horizon: int = 1000,
    ) -> dict:
        """Plays ``episodes`` seeded starts on each goal (``goals`` ``:``-separated, default
        every goal) in the model's own world, with ``epsilon`` (default :attr:`default_epsilon`,
        as ``eval``'s), and returns what ``blockstack eval --model PATH --json`` prints with the
        same settings."""
        episodes = whole("episodes", episodes)
        seed = whole("seed", seed)
        horizon = whole("horizon", horizon, 0, U32_MAX)
        if epsilon is not None and (
            isinstance(epsilon, bool) or not isinstance(epsilon, (int, float, np.integer, np.floating))
        ):
            raise ValueError(f"epsilon is a probability (a number in [0, 1]), not {epsilon!r}")
        for name, value in (("goals", goals), ("backend", backend)):
            if value is not None and not isinstance(value, str):
                raise ValueError(f"{name} is text, not {value!r}")
        epsilon = None if epsilon is None else float(epsilon)
        return json.loads(self._native.evaluate(episodes, seed, goals, epsilon, backend, horizon))


def _whole_array(name: str, value: Any) -> np.ndarray:
    """``observation[name]`` as an array of whole numbers (:func:`whole_numbers`)."""
    return whole_numbers(f"observation[{name!r}]", value)


def load(path: Union[str, os.PathLike]) -> Model:
    """The model file at ``path``, of any kind; a ``ValueError`` saying what is wrong with a
    file that is none."""
    return Model(path)
