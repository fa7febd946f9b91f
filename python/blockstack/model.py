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
show it. A relational policy plays the side view at any number of blocks, a block move at a
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
from blockstack.env import StackEnv

# The test policy's exploration when ``deterministic=False`` (the paper's test epsilon).
TEST_EPSILON = 0.1


class Model:
    """A trained model read from a file (:func:`load`)."""

    def __init__(self, path: Union[str, os.PathLike]):
        self._native = _native.NativeModel(os.fspath(path))
        self.path = os.fspath(path)

    @property
    def kind(self) -> str:
        """``q`` (a tabular Q-agent), ``dqn`` (a network) or ``relational`` (a relational
        policy of block moves)."""
        return self._native.kind

    @property
    def name(self) -> str:
        """The model's name in reports."""
        return self._native.name

    @property
    def world(self) -> dict:
        """The world it was trained in, as :class:`blockstack.StackEnv` keyword arguments."""
        return self._native.world()

    def make_env(self, **overrides: Any) -> StackEnv:
        """A Gymnasium environment of the world the model was trained in, showing the
        ``state`` observation that :meth:`predict` reads; ``overrides`` change any keyword
        argument of :class:`blockstack.StackEnv` (``goal``, ``backend``, ``render_mode``...)."""
        kwargs = dict(self.world, obs="state")
        if self.kind == "relational":
            kwargs["actions"] = "moves"
        kwargs.update(overrides)
        return StackEnv(**kwargs)

    def reset(self, seed: int) -> None:
        """Starts the policy's generator for an episode reset with ``seed``, as ``blockstack
        run`` does, so that ties are broken as the CLI breaks them."""
        self._native.reset(int(seed))

    def predict(
        self,
        observation: dict,
        state: Any = None,
        episode_start: Optional[np.ndarray] = None,
        deterministic: bool = True,
        grid: Optional[Tuple[int, int]] = None,
    ) -> Tuple[int, None]:
        """``(action, None)`` for a ``state`` observation: the greedy legal action, or with
        ``deterministic=False`` a random legal action with probability 0.1 (the paper's test
        policy). For a relational policy the action is a block move of an environment with
        ``actions="moves"`` on ``grid`` (default: the model's world's grid). ``state`` and
        ``episode_start`` are Stable-Baselines3's arguments for recurrent policies, unused
        here."""
        if not isinstance(observation, dict) or not {"blocks", "held", "goal"} <= set(observation):
            raise ValueError(
                "predict reads the state observation (a dict of blocks, held and goal): make the "
                "environment with obs='state', as model.make_env() does"
            )
        cells = [tuple(int(v) for v in c) for c in np.asarray(observation["blocks"])]
        held = int(observation["held"])
        goal = [int(b) for b in np.asarray(observation["goal"])]
        # Without ``goal_tower`` (observations of releases before it) the goal is one tower.
        towers = [int(t) for t in np.asarray(observation.get("goal_tower", [0] * len(goal)))]
        epsilon = 0.0 if deterministic else TEST_EPSILON
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
        epsilon: float = TEST_EPSILON,
        backend: str = "physics",
        horizon: int = 1000,
    ) -> dict:
        """Plays ``episodes`` seeded starts on each goal (``goals`` ``:``-separated, default
        every goal) in the model's own world and returns what ``blockstack eval --model PATH
        --json`` prints with the same settings."""
        return json.loads(self._native.evaluate(episodes, seed, goals, epsilon, backend, horizon))


def load(path: Union[str, os.PathLike]) -> Model:
    """The model file at ``path``, of any kind; a ``ValueError`` saying what is wrong with a
    file that is none."""
    return Model(path)
