"""blockstack: a physics-backed 2D block-stacking world for reinforcement learning.

Importing the package registers ``blockstack/Stack-v0`` (and ``blockstack/BlocksWorld-v0``,
the classic Blocks World seen from the side) with Gymnasium::

    import gymnasium as gym
    import blockstack

    env = gym.make("blockstack/Stack-v0", blocks=3, obs="planes")
    obs, info = env.reset(seed=7)   # the start of the Rust ``Env::reset(7)``
    obs, reward, terminated, truncated, info = env.step(env.unwrapped.expert_action())

- :class:`StackEnv`: the Gymnasium environment (``gymnasium.make``).
- :class:`StackGoalEnv`: the same world as a goal-conditioned environment
  (``blockstack/StackGoal-v0``: observation, achieved and desired goals, and
  ``compute_reward``), on which Stable-Baselines3's ``HerReplayBuffer`` runs.
- :class:`blockstack.vector.StackVectorEnv`: a batch of environments stepped in one Rust
  call into preallocated numpy arrays.
- :func:`solve`: a shortest (or the oracle's) plan from any state.
- :func:`demonstrations` and :func:`read_recording`: expert trajectories, and the CLI's
  recordings, as dicts of numpy arrays; :func:`to_minari`: recordings as a Minari
  dataset for offline learners.
- :func:`load`: a trained model file of any kind (q, dqn, relational), played and evaluated with
  Stable-Baselines3's conventions (:class:`Model`).
- :func:`train`: the Rust tabular trainer, in-process; ``python -m blockstack.sweep`` runs
  grids of it on Ray.
- :func:`train_dqn`: the Rust network trainer (``blockstack dqn``), in-process.

The world, its rules, rewards, planners and trainer are the Rust crates' (``sim``,
``oracle``, ``agent``); this package only carries arguments in and arrays out. Every error
they report is raised as ``ValueError`` with their message.
"""

from gymnasium.envs.registration import register, registry

from blockstack import _native
from blockstack._checks import whole
from blockstack._native import REWARDS
from blockstack.demonstrations import demonstrations, read_recording
from blockstack.env import BlocksWorldEnv, StackEnv
from blockstack.goal_env import StackGoalEnv
from blockstack.minari import to_minari
from blockstack.model import Model, load
from blockstack import vector
from blockstack.planning import read_pddl, solve, solve_all, solve_pddl
from blockstack.training import train, train_dqn
from blockstack.world import World

__all__ = [
    "REWARDS",
    "BlocksWorldEnv",
    "Model",
    "StackEnv",
    "StackGoalEnv",
    "World",
    "demonstrations",
    "episode_seed",
    "load",
    "read_pddl",
    "read_recording",
    "solve",
    "solve_all",
    "solve_pddl",
    "to_minari",
    "train",
    "train_dqn",
    "vector",
]

def episode_seed(base: int, index: int) -> int:
    """The seed of episode ``index`` of a run with seed ``base``: the seed ``blockstack run
    --seed BASE`` resets its episode ``index`` with (``sim::seeding::episode_seed``)."""
    return _native.episode_seed(whole("base", base), whole("index", index))


ENV_ID = "blockstack/Stack-v0"

if ENV_ID not in registry:
    register(
        id=ENV_ID,
        entry_point="blockstack.env:StackEnv",
        vector_entry_point="blockstack.vector:StackVectorEnv",
    )

#: The classic Blocks World, seen from the side (:class:`BlocksWorldEnv`).
BLOCKS_WORLD_ID = "blockstack/BlocksWorld-v0"

if BLOCKS_WORLD_ID not in registry:
    register(id=BLOCKS_WORLD_ID, entry_point="blockstack.env:BlocksWorldEnv")

GOAL_ENV_ID = "blockstack/StackGoal-v0"

if GOAL_ENV_ID not in registry:
    register(id=GOAL_ENV_ID, entry_point="blockstack.goal_env:StackGoalEnv")
