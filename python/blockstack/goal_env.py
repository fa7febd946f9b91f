"""``blockstack/StackGoal-v0``: the world as a goal-conditioned environment.

Gymnasium-Robotics' ``GoalEnv`` convention, which hindsight experience replay (HER,
Andrychowicz et al. 2017) needs: the observation is a dict of ``observation``,
``achieved_goal`` and ``desired_goal``, and ``compute_reward(achieved_goal, desired_goal,
info)`` gives the reward for any pair, one or a batch. Stable-Baselines3's
``HerReplayBuffer`` runs on it unchanged::

    import gymnasium as gym
    import blockstack
    from stable_baselines3 import DQN, HerReplayBuffer

    env = gym.make("blockstack/StackGoal-v0", blocks=2)
    model = DQN("MultiInputPolicy", env, replay_buffer_class=HerReplayBuffer)

Goals are stacks anywhere on the grid: a goal is its block ids bottom to top, and the goal
a state achieves is the stack standing in it (computed by the Rust ``sim``, the one home of
the rules), or ``-1`` for every block when no stack stands (no goal equals it).
"""

from __future__ import annotations

from typing import Any, Optional

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from blockstack import _native
from blockstack._checks import whole_numbers
from blockstack.env import StackEnv
from blockstack.spaces import action_space, observation_space

#: The rewards a goal environment takes: those that depend only on whether the goal holds.
GOAL_REWARDS = ("sparse", "step-cost")


class StackGoalEnv(gym.Env):
    """Blocks to stack in a goal's order, with the goal beside the observation.

    Arguments (keyword, as ``gymnasium.make("blockstack/StackGoal-v0", ...)`` passes them):
    the world keywords of :mod:`blockstack.world`, as every environment takes them,
    ``render_mode`` and ``strict`` (as :class:`blockstack.StackEnv` takes them: an action
    the world's rules refuse changes nothing, ``info["illegal"]``). Two differ here:

    - ``reward``: ``sparse`` (+10 at the goal, the default) or ``step-cost`` (-1 a step, 0
      at the goal): a goal environment's reward is a function of the achieved and desired
      goals alone, which the others (they weigh distances or moves) are not.
    - ``goal``: one stack of every block (``"1,0,2"``), or ``None`` to draw one each
      episode. A goal of towers (``"0,1/2"``) is refused: the goal a state achieves is the
      stack standing in it, which a goal leaving blocks free is not, so the environment
      would pay for goals that ``compute_reward`` never sees reached.

    Observation: a dict of

    - ``observation``: the block-id ``planes`` (``uint8`` 0/1, ``(W, H, N + 1)``), which do
      not depend on the goal (``role-planes`` and ``frame`` do, so a relabelled goal would
      contradict them);
    - ``desired_goal``: the episode's goal, ``int64`` ``(N,)``, bottom to top;
    - ``achieved_goal``: the stack standing now (in the side view, on the table with no
      block of it held), or ``-1`` everywhere.

    ``info`` is :class:`blockstack.StackEnv`'s with ``is_success`` (the goal holds; what
    Stable-Baselines3 logs as the success rate) and ``steps`` (steps of the episode).
    ``terminated`` is ``compute_terminated(...)``, ``truncated`` ``compute_truncated(...)``
    and ``reward`` ``compute_reward(...)`` of the step's achieved and desired goals and info.
    """

    metadata = {"render_modes": ["rgb_array", "ansi"], "render_fps": 4}

    def __init__(self, render_mode: Optional[str] = None, strict: bool = False, **world: Any):
        reward = world.setdefault("reward", "sparse")
        if reward not in GOAL_REWARDS:
            # The Rust side says why; asked here so the error comes before the world is made.
            _native.goal_rewards(str(reward), 2, (7, 7))
        self._env = StackEnv(obs="planes", render_mode=render_mode, strict=strict, **world)
        self.world = self._env.world
        if self.world.goal is not None:
            _native.check_stack_goal(self.world.goal, self.world.blocks)
        native = self._env._native
        self.blocks = native.blocks
        self.horizon = native.horizon
        self.render_mode = render_mode
        self._reached, self._missed = _native.goal_rewards(reward, self.blocks, native.grid)
        goal_space = spaces.Box(-1, self.blocks - 1, shape=(self.blocks,), dtype=np.int64)
        self.action_space = action_space(self.blocks)
        self.observation_space = spaces.Dict(
            {
                "observation": observation_space("planes", self.blocks, native.grid),
                "achieved_goal": goal_space,
                "desired_goal": goal_space,
            }
        )

    def _observe(self, planes: np.ndarray, info: dict) -> dict:
        cells, held, goal = self._env._native.state()
        achieved = np.array(_native.achieved_goal(cells, held, self.world.view), dtype=np.int64)
        info["is_success"] = bool(np.array_equal(achieved, goal))
        info["steps"] = self._env._native.steps
        return {
            "observation": planes,
            "achieved_goal": achieved,
            "desired_goal": np.array(goal, dtype=np.int64),
        }

    def reset(self, *, seed: Optional[int] = None, options: Optional[dict] = None):
        planes, info = self._env.reset(seed=seed, options=options)
        super().reset(seed=seed)
        return self._observe(planes, info), info

    def step(self, action):
        planes, reward, terminated, truncated, info = self._env.step(action)
        obs = self._observe(planes, info)
        return obs, reward, terminated, truncated, info

    def compute_reward(self, achieved_goal: Any, desired_goal: Any, info: Any) -> Any:
        """The reward of a step after which ``achieved_goal`` stands, towards
        ``desired_goal``: one pair (``(N,)`` each; a float) or a batch (``(B, N)`` each; an
        array of ``B``). ``info`` is not read (the reward depends on the goals alone)."""
        reached = self.compute_terminated(achieved_goal, desired_goal, info)
        rewards = np.where(reached, self._reached, self._missed)
        return float(rewards) if np.ndim(rewards) == 0 else rewards

    def compute_terminated(self, achieved_goal: Any, desired_goal: Any, info: Any) -> Any:
        """Whether ``desired_goal`` holds where ``achieved_goal`` stands, pair by pair."""
        achieved = np.asarray(achieved_goal)
        desired = np.asarray(desired_goal)
        if achieved.shape != desired.shape or achieved.shape[-1:] != (self.blocks,):
            raise ValueError(
                f"achieved and desired goals are arrays of shape ({self.blocks},) or (batch, {self.blocks}), "
                f"not {achieved.shape} and {desired.shape}"
            )
        # Block ids: whole numbers (a replay buffer may hold them as floats), never rounded.
        achieved = whole_numbers("achieved_goal", achieved)
        desired = whole_numbers("desired_goal", desired)
        reached = np.all(achieved == desired, axis=-1) & np.all(desired >= 0, axis=-1)
        return bool(reached) if reached.ndim == 0 else reached

    def compute_truncated(self, achieved_goal: Any, desired_goal: Any, info: Any) -> Any:
        """Whether the episode is cut off at the horizon: ``info["steps"]`` reached it and the
        goal does not hold (one pair, or a batch with a list of infos)."""
        reached = self.compute_terminated(achieved_goal, desired_goal, info)
        if isinstance(info, dict):
            return bool(not reached and info["steps"] >= self.horizon)
        steps = np.array([i["steps"] for i in info])
        return ~reached & (steps >= self.horizon)

    def render(self):
        return self._env.render()

    def expert_action(self) -> int:
        """The exact solver's next action under the world's rules: the first of a shortest
        legal plan from here."""
        return self._env.expert_action()

    def optimal_steps(self) -> int:
        """The length of a shortest plan from here to the desired goal."""
        return self._env._native.optimal_steps()

    def __reduce__(self):
        raise TypeError(
            "a StackGoalEnv cannot be pickled or copied (its Rust world and generator are not Python objects): "
            "make another with the same arguments"
        )
