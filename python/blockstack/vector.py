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
from typing import Any, Optional, Sequence, Union

import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from blockstack import _native
from blockstack._checks import ENV_BYTES, fits_in_memory, observation_bytes, whole
from blockstack.env import check_seed
from blockstack.spaces import action_space, observation_space
from blockstack.world import world_of

#: Below this many environments one thread steps the batch, whatever ``threads`` says
#: (``sim::vec_env::PARALLEL_FROM_ENVS``): a hand-off to another thread costs about what it
#: saves (measured by ``cargo bench -p sim --bench vec_env``; docs/performance.md).
PARALLEL_FROM_ENVS: int = _native.PARALLEL_FROM_ENVS

_MODES = {AutoresetMode.NEXT_STEP: "next-step", AutoresetMode.SAME_STEP: "same-step"}
#: The spellings taken for each mode: Gymnasium's values and the native side's names.
_SPELLINGS = {spelling: mode for mode, name in _MODES.items() for spelling in (mode.value, name)}
_INFO_KEYS = ("action_mask", "blocked", "illegal", "pairs_in_place", "goal", "goal_tower")


def _cores() -> int:
    """The cores this process may run on."""
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1


class StackVectorEnv(VectorEnv):
    """``num_envs`` blockstack environments of one world, stepped together in Rust.

    Takes the world keywords of :mod:`blockstack.world`, as every environment does,
    ``obs`` and ``render_mode`` as :class:`blockstack.StackEnv` takes them (gripper actions
    only), and:

    - ``threads``: threads that step the batch; ``None`` picks one below
      :data:`PARALLEL_FROM_ENVS` environments and one per core from there.
    - ``autoreset_mode``: ``AutoresetMode.NEXT_STEP`` (Gymnasium's default: the step after
      an episode ends resets that environment, ignoring its action, with reward 0) or
      ``SAME_STEP`` (the ending step resets it and reports the last observation and info
      in ``infos["final_obs"]`` / ``infos["final_info"]``). Declared in ``metadata``.
    - ``copy``: ``True`` (Gymnasium's default) returns copies; ``False`` returns the
      buffers themselves, overwritten by the next call (the fastest way to read them).
    - ``strict``: as :class:`blockstack.StackEnv` takes it. By default an action the
      world's rules refuse is a step that changes nothing, marked in ``infos["illegal"]``;
      with ``strict=True`` it is a ``ValueError`` and nothing is stepped.

    ``num_envs`` is refused with a ``ValueError`` when the buffers and environments would
    need more than the machine's physical memory (about 8 KiB and an observation each).
    One instance may be used from
    several threads: its calls take turns. It cannot be pickled or copied.

    ``reset(seed=s)`` resets environment ``i`` with ``s + i`` (a list gives one seed each),
    as ``SyncVectorEnv`` does; ``reset()`` continues every environment's generator.
    """

    metadata = {"render_modes": ["rgb_array"], "autoreset_mode": AutoresetMode.NEXT_STEP}

    def __init__(
        self,
        num_envs: int,
        obs: str = "planes",
        render_mode: Optional[str] = None,
        threads: Optional[int] = None,
        autoreset_mode: Union[AutoresetMode, str] = AutoresetMode.NEXT_STEP,
        copy: bool = True,
        strict: bool = False,
        **world: Any,
    ):
        key = autoreset_mode.value if isinstance(autoreset_mode, AutoresetMode) else autoreset_mode
        mode = _SPELLINGS.get(key) if isinstance(key, str) else None
        if mode is None:
            raise ValueError(f"autoreset mode {autoreset_mode!r} is not supported: use next-step or same-step")
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"cannot read render mode from {render_mode!r}: choose None or rgb_array")
        if not isinstance(obs, str):
            raise ValueError(f"obs is a name (text), not {obs!r}")
        num_envs = whole("num_envs", num_envs)
        #: The world every environment plays (:class:`blockstack.world.World`).
        self.world = world_of(world)
        blocks, grid = self.world.blocks, self.world.grid
        if threads is None:
            threads = 1 if num_envs < PARALLEL_FROM_ENVS else _cores()
        threads = whole("threads", threads, 0, 4096)
        # Every buffer and environment, counted before any is made: an allocation that
        # fails in Rust would abort the interpreter.
        per_env = observation_bytes(obs, blocks, grid) + 8 * (blocks + 2) + (5 + blocks) + 4 + ENV_BYTES
        fits_in_memory(f"num_envs={num_envs}", num_envs * per_env)
        if not isinstance(strict, bool):
            raise ValueError(f"strict is True or False, not {strict!r}")
        self._native = _native.NativeVecEnv(num_envs, self.world, obs, threads, _MODES[mode], strict)
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
        # Every info key is present for every environment: one mask, made once (read-only,
        # as the buffers are the caller's to read, not to write; copies when ``copy``).
        self._every_env = np.ones(num_envs, dtype=bool)
        self._every_env.flags.writeable = False
        # Without copies, the infos of a step are the same arrays every time: a fresh dict of
        # them per step (the caller may add keys) costs less than building it key by key,
        # which every step pays on the caller's thread alone.
        self._shared_infos = {}
        for key in _INFO_KEYS:
            self._shared_infos[key] = self._buffers[key]
            self._shared_infos["_" + key] = self._every_env

    def _out(self, value):
        if isinstance(value, dict):
            return {k: self._out(v) for k, v in value.items()}
        return value.copy() if self.copy else value

    def _infos(self, ended: Sequence) -> dict:
        n = self.num_envs
        infos = self._out(self._shared_infos) if self.copy else dict(self._shared_infos)
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
        if actions.dtype == np.uint64 and actions.size:
            # Checked here, in Python's integers: a uint64 beyond int64 would wrap natively.
            # The native step checks every other integer type itself.
            count, value = self.single_action_space.n, int(actions.max())
            if value >= count:
                raise ValueError(f"action {value} is out of range: with {count - 5} blocks the actions are 0..{count}")
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
