"""``StackVectorEnv``: many blockstack environments stepped in one Rust call.

Each :meth:`StackVectorEnv.step` hands the whole action array to Rust, which releases the
GIL, steps every environment (on several threads for large batches) and writes
observations, rewards, terminations, truncations and infos straight into numpy arrays
allocated once: no Python object per environment. It behaves exactly as
``gymnasium.vector.SyncVectorEnv`` of the same environments with the same seeds, in
either autoreset mode (the tests check it step for step).
"""

from __future__ import annotations

import os
import threading
from typing import Optional, Sequence, Tuple, Union

import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from blockstack import _native
from blockstack._checks import ENV_BYTES, U32_MAX, fits_in_memory, observation_bytes, whole
from blockstack._goal import Goal, goal_text
from blockstack.env import check_seed
from blockstack.spaces import action_space, observation_space

#: Below this many environments one thread steps the batch (``threads=None``): a hand-off
#: to other threads costs more than it saves (measured by ``benchmarks/python/throughput.py``).
PARALLEL_FROM_ENVS = 256

_MODES = {AutoresetMode.NEXT_STEP: "next-step", AutoresetMode.SAME_STEP: "same-step"}
#: The spellings taken for each mode: Gymnasium's values and the native side's names.
_SPELLINGS = {spelling: mode for mode, name in _MODES.items() for spelling in (mode.value, name)}
_INFO_KEYS = ("action_mask", "blocked", "pairs_in_place", "goal", "goal_tower")


def _cores() -> int:
    """The cores this process may run on."""
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1


class StackVectorEnv(VectorEnv):
    """``num_envs`` blockstack environments of one world, stepped together in Rust.

    Takes the keyword arguments of :class:`blockstack.StackEnv` and:

    - ``threads``: threads that step the batch; ``None`` picks one below
      :data:`PARALLEL_FROM_ENVS` environments and one per core from there.
    - ``autoreset_mode``: ``AutoresetMode.NEXT_STEP`` (Gymnasium's default: the step after
      an episode ends resets that environment, ignoring its action, with reward 0) or
      ``SAME_STEP`` (the ending step resets it and reports the last observation and info
      in ``infos["final_obs"]`` / ``infos["final_info"]``). Declared in ``metadata``.
    - ``view``: ``top`` (the paper's world) or ``side`` (the Blocks World seen from the side,
      as ``blockstack/BlocksWorld-v0``; gripper actions).
    - ``copy``: ``True`` (Gymnasium's default) returns copies; ``False`` returns the
      buffers themselves, overwritten by the next call (the fastest way to read them).

    ``num_envs`` is refused with a ``ValueError`` when the buffers and environments would
    need more than the machine's physical memory (about 8 KiB and an observation each).
    ``grid`` is ``(width, height)`` or text such as ``"7x7"`` (default: as ``StackEnv``'s). One instance may be used from
    several threads: its calls take turns. It cannot be pickled or copied.

    ``reset(seed=s)`` resets environment ``i`` with ``s + i`` (a list gives one seed each),
    as ``SyncVectorEnv`` does; ``reset()`` continues every environment's generator.
    """

    metadata = {"render_modes": ["rgb_array"], "autoreset_mode": AutoresetMode.NEXT_STEP}

    def __init__(
        self,
        num_envs: int,
        blocks: int = 3,
        goal: Goal = None,
        grid: Optional[Tuple[int, int]] = None,
        reward: Optional[str] = None,
        backend: str = "physics",
        obs: str = "planes",
        profile: str = "spec",
        render_mode: Optional[str] = None,
        max_episode_steps: int = 1000,
        horizon: Optional[int] = None,
        threads: Optional[int] = None,
        autoreset_mode: Union[AutoresetMode, str] = AutoresetMode.NEXT_STEP,
        copy: bool = True,
        view: str = "top",
    ):
        key = autoreset_mode.value if isinstance(autoreset_mode, AutoresetMode) else autoreset_mode
        mode = _SPELLINGS.get(key) if isinstance(key, str) else None
        if mode is None:
            raise ValueError(f"autoreset mode {autoreset_mode!r} is not supported: use next-step or same-step")
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"cannot read render mode from {render_mode!r}: choose None or rgb_array")
        num_envs = whole("num_envs", num_envs)
        blocks = whole("blocks", blocks)
        grid = _native.grid_size(grid, view, blocks)
        steps = whole("max_episode_steps", max_episode_steps, 0, U32_MAX)
        if horizon is not None:
            steps = whole("horizon", horizon, 0, U32_MAX)
        if threads is None:
            threads = 1 if num_envs < PARALLEL_FROM_ENVS else _cores()
        threads = whole("threads", threads, 0, 4096)
        # Every buffer and environment, counted before any is made: an allocation that
        # fails in Rust would abort the interpreter.
        per_env = observation_bytes(obs, blocks, grid) + 8 * (blocks + 2) + (5 + blocks) + 3 + ENV_BYTES
        fits_in_memory(f"num_envs={num_envs}", num_envs * per_env)
        self._native = _native.NativeVecEnv(
            num_envs, blocks, goal_text(goal), grid, reward, backend, steps, profile, obs, threads, _MODES[mode], view
        )
        self._lock = threading.Lock()
        self.metadata = dict(self.metadata, autoreset_mode=mode)
        self.autoreset_mode = mode
        self.num_envs = num_envs
        self.threads = threads
        self.copy = copy
        self.render_mode = render_mode
        self.single_action_space = action_space(blocks)
        self.single_observation_space = observation_space(obs, blocks, grid)
        self.action_space = batch_space(self.single_action_space, num_envs)
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self._buffers = self._native.buffers()

    def _out(self, value):
        if isinstance(value, dict):
            return {k: self._out(v) for k, v in value.items()}
        return value.copy() if self.copy else value

    def _infos(self, ended: Sequence) -> dict:
        n = self.num_envs
        infos = {}
        for key in _INFO_KEYS:
            infos[key] = self._out(self._buffers[key])
            infos["_" + key] = np.ones(n, dtype=bool)
        if ended:
            final_obs = np.full(n, None, dtype=object)
            has_final = np.zeros(n, dtype=bool)
            final_info = {}
            for key in _INFO_KEYS:
                column = self._buffers[key]
                final_info[key] = np.zeros_like(column)
                final_info["_" + key] = has_final.copy()
            for i, obs, info in ended:
                final_obs[i] = obs
                has_final[i] = True
                for key in _INFO_KEYS:
                    final_info[key][i] = info[key]
                    final_info["_" + key][i] = True
            infos["final_obs"] = final_obs
            infos["_final_obs"] = has_final
            infos["final_info"] = final_info
            infos["_final_info"] = has_final.copy()
        return infos

    def reset(self, *, seed: Union[int, Sequence[Optional[int]], None] = None, options: Optional[dict] = None):
        n = self.num_envs
        if options:
            raise ValueError(f"StackVectorEnv.reset takes no options (given {sorted(options)}): reset with seeds only")
        if seed is None:
            seeds = [None] * n
        elif isinstance(seed, (int, np.integer)) and not isinstance(seed, bool):
            seeds = [check_seed(seed + i) for i in range(n)]
        else:
            seeds = [check_seed(s) for s in seed]
            if len(seeds) != n:
                raise ValueError(f"{len(seeds)} seeds given for {n} environments: give one per environment")
        if seed is not None:
            self._np_random_seed = seeds[0]
        # One call at a time writes the shared buffers; the results are read under the
        # same turn, so two threads never see each other's half-written arrays.
        with self._lock:
            self._native.reset(seeds)
            return self._out(self._buffers["obs"]), self._infos(())

    def step(self, actions):
        actions = np.asarray(actions)
        if actions.dtype.kind in "iu" and actions.size:
            count = self.single_action_space.n
            # Checked here, in Python's integers: a uint64 beyond int64 would wrap natively.
            for value in (actions.min(), actions.max()):
                if not 0 <= int(value) < count:
                    raise ValueError(
                        f"action {int(value)} is out of range: with {count - 5} blocks the actions are 0..{count}"
                    )
        with self._lock:
            ended = self._native.step(actions)
            b = self._buffers
            return (
                self._out(b["obs"]),
                b["rewards"].copy() if self.copy else b["rewards"],
                b["terminations"].copy() if self.copy else b["terminations"],
                b["truncations"].copy() if self.copy else b["truncations"],
                self._infos(ended),
            )

    def __reduce__(self):
        raise TypeError(
            "a StackVectorEnv cannot be pickled or copied (its Rust worlds and generators are not "
            "Python objects): make another with the same arguments"
        )

    def render(self):
        if self.render_mode == "rgb_array":
            with self._lock:
                return tuple(self._native.render_rgb(i) for i in range(self.num_envs))
        return None

    def action_masks(self) -> np.ndarray:
        """The legal actions of every environment now, ``(num_envs, 5 + N)`` booleans."""
        return self._buffers["action_mask"].astype(bool)
