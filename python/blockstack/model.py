"""Trained models: ``blockstack.load(path)`` reads a model file of either kind (a tabular
Q-agent from ``blockstack train``, a network from ``blockstack dqn``) and plays it with
Stable-Baselines3's conventions::

    model = blockstack.load("role.safetensors")
    env = model.make_env()                      # the world it was trained in, obs="state"
    obs, info = env.reset(seed=7)
    model.reset(7)                              # break ties as `blockstack run` would
    action, _ = model.predict(obs, deterministic=True)
    report = model.evaluate(episodes=100, seed=2)   # what `blockstack eval --json` prints

``predict`` reads the ``state`` observation (a dict of ``blocks``, ``held``, ``goal`` and
``goal_tower``), which holds everything either kind of model needs, and ``make_env`` makes
environments that show it; a network on pixels also plays on its own picture
(``make_env(obs=model.picture)``, ``predict(obs, info=info)``).
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
        """``q`` (a tabular Q-agent) or ``dqn`` (a network)."""
        return self._native.kind

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
        argument of :class:`blockstack.StackEnv` (``goal``, ``backend``, ``render_mode``...)."""
        kwargs = dict(self.world, obs="state")
        kwargs.update(overrides)
        return StackEnv(**kwargs)

    def reset(self, seed: int) -> None:
        """Starts the policy's generator for an episode reset with ``seed``, as ``blockstack
        run`` does, so that ties are broken as the CLI breaks them."""
        self._native.reset(int(seed))

    def predict(
        self,
        observation: Union[dict, np.ndarray],
        state: Any = None,
        episode_start: Optional[np.ndarray] = None,
        deterministic: bool = True,
        info: Optional[dict] = None,
    ) -> Tuple[int, None]:
        """``(action, None)``: the greedy action, or with ``deterministic=False`` a random
        legal action with probability 0.1 (the paper's test policy). ``state`` and
        ``episode_start`` are Stable-Baselines3's arguments for recurrent policies, unused
        here.

        ``observation`` is the ``state`` observation (a dict of ``blocks``, ``held``, ``goal``
        and ``goal_tower``), which either kind of model plays as ``blockstack run`` does; or,
        for a network on pixels, the picture it reads (the environment's ``paper-screen``, or
        ``screen`` for a ``pixels`` network) with the step's ``info`` (its ``goal``,
        ``goal_tower`` and ``action_mask``): greedy among the legal actions, since the
        no-op mask ``blockstack run`` adds needs the state."""
        epsilon = 0.0 if deterministic else TEST_EPSILON
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
        cells = [tuple(int(v) for v in c) for c in np.asarray(observation["blocks"])]
        held = int(observation["held"])
        goal = [int(b) for b in np.asarray(observation["goal"])]
        # Without ``goal_tower`` (observations of releases before it) the goal is one tower.
        towers = [int(t) for t in np.asarray(observation.get("goal_tower", [0] * len(goal)))]
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
    """The model file at ``path``, of either kind; a ``ValueError`` saying what is wrong with
    a file that is neither."""
    return Model(path)
