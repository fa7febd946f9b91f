"""Steps per second of blockstack beside MiniGrid and FrozenLake, through the same paths.

    python python/benchmarks/throughput.py [--seconds 2] [--quick] [--view top|side] [--blocks 3]
    python python/benchmarks/throughput.py --scaling 7 [--seconds 0.5] [--sizes 256,512,1024]

Prints one table: (a) ``blockstack/Stack-v0`` through ``gymnasium.make``, one env, random
legal actions; (b) the same through ``gymnasium.vector.SyncVectorEnv`` of 64; (c)
``StackVectorEnv`` with 64, 256, 1024 and 4096 envs on 1 and 2 threads (``copy=False``: the
buffers are read in place, as PufferLib-style trainers do); (d) MiniGrid-Empty-8x8 and
FrozenLake through (a) and (b). Every row uses the physics backend and ``planes``
observations unless it says otherwise; actions are drawn uniformly from the legal ones
(``info["action_mask"]``), and episodes reset as they end. MiniGrid is optional
(``pip install minigrid``); its rows are skipped without it.

``--view side`` measures the side view instead (``blockstack/BlocksWorld-v0``, and
``StackVectorEnv(view="side")``), where the random legal actions include drops that run
rapier's dynamics until the blocks rest; the native vector env's actions are then drawn
among the legal ones (``action_masks()``) too, that draw included in the time. The peers
are left out. ``--blocks`` sets the block count of every blockstack row (3 by default).

``--scaling PAIRS`` prints, instead of the table, what a second thread buys
``StackVectorEnv`` on either backend at each of ``--sizes``: PAIRS runs on 1 thread
alternated with PAIRS on 2, ``--seconds`` each, and their medians and the median of the
pairs' ratios. Alternated short runs and medians, since a shared machine's load moves a
single run by a third.
"""

from __future__ import annotations

import argparse
import statistics
import time

import gymnasium as gym
import numpy as np
from gymnasium.vector import SyncVectorEnv

import blockstack
from blockstack.vector import StackVectorEnv


def timed(step, seconds: float) -> float:
    """Calls ``step()`` (which returns the env-steps it took) for about ``seconds``; env-steps per second."""
    step()  # warm up
    steps, start = 0, time.perf_counter()
    while True:
        for _ in range(8):
            steps += step()
        elapsed = time.perf_counter() - start
        if elapsed >= seconds:
            return steps / elapsed


def single(make, seconds: float) -> float:
    env = make()
    rng = np.random.default_rng(0)
    state = {"info": env.reset(seed=0)[1]}
    n = env.action_space.n

    def step():
        mask = state["info"].get("action_mask")
        legal = np.flatnonzero(mask) if mask is not None else None
        for _ in range(100):
            a = int(legal[rng.integers(len(legal))]) if legal is not None else int(rng.integers(n))
            _, _, terminated, truncated, info = env.step(a)
            if terminated or truncated:
                _, info = env.reset()
            if mask is not None:
                legal = np.flatnonzero(info["action_mask"])
        return 100

    return timed(step, seconds)


def sync(make, num_envs: int, seconds: float) -> float:
    envs = SyncVectorEnv([make for _ in range(num_envs)])
    envs.reset(seed=0)
    rng = np.random.default_rng(0)
    n = envs.single_action_space.n

    def step():
        envs.step(rng.integers(0, n, size=num_envs))
        return num_envs

    return timed(step, seconds)


def native(num_envs: int, threads: int, seconds: float, **kwargs) -> float:
    envs = StackVectorEnv(num_envs, threads=threads, copy=False, **kwargs)
    envs.reset(seed=0)
    rng = np.random.default_rng(0)
    n = envs.single_action_space.n
    k = [0]
    if kwargs.get("view") == "side":
        # Only some actions are legal in the side view: each env takes the legal action with
        # the largest of n random keys, drawn ahead in batches.
        keys = [rng.random((num_envs, n)) + 1.0 for _ in range(16)]

        def step():
            k[0] = (k[0] + 1) % len(keys)
            envs.step(np.argmax(keys[k[0]] * envs.action_masks(), axis=1))
            return num_envs

        return timed(step, seconds)
    # Every action is legal in the spec world; a batch of random ones per step, drawn ahead.
    batches = [rng.integers(0, n, size=num_envs) for _ in range(16)]

    def step():
        k[0] = (k[0] + 1) % len(batches)
        envs.step(batches[k[0]])
        return num_envs

    return timed(step, seconds)


def scaling(pairs: int, seconds: float, sizes: list[int], **world) -> None:
    """1 thread against 2 at each size and backend: medians of alternated runs."""
    print(f"  {'backend':<8} {'envs':>6} {'1 thread':>12} {'2 threads':>12} {'ratio':>7} {'range':>12}")
    for backend in ("physics", "grid"):
        for num_envs in sizes:
            one, two = [], []
            for _ in range(pairs):
                one.append(native(num_envs, 1, seconds, backend=backend, **world))
                two.append(native(num_envs, 2, seconds, backend=backend, **world))
            ratios = sorted(b / a for a, b in zip(one, two))
            print(
                f"  {backend:<8} {num_envs:>6} {statistics.median(one):>12,.0f} {statistics.median(two):>12,.0f}"
                f" {statistics.median(ratios):>6.2f}x {ratios[0]:>5.2f}-{ratios[-1]:.2f}x",
                flush=True,
            )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=2.0, help="time per row")
    parser.add_argument("--quick", action="store_true", help="skip 4096 envs and the peers")
    parser.add_argument("--view", choices=["top", "side"], default="top", help="the world measured")
    parser.add_argument("--blocks", type=int, default=3, help="blocks in every blockstack env")
    parser.add_argument("--scaling", type=int, metavar="PAIRS", help="1 thread against 2: PAIRS alternated runs each")
    parser.add_argument("--sizes", default="256,512,1024,2048,4096", help="envs measured by --scaling")
    args = parser.parse_args()
    s = args.seconds
    side = args.view == "side"
    if args.scaling:
        scaling(args.scaling, s, [int(n) for n in args.sizes.split(",")], blocks=args.blocks, view=args.view)
        return
    name = "blockstack/BlocksWorld-v0" if side else "blockstack/Stack-v0"
    world = {"blocks": args.blocks, "view": args.view}
    rows = []

    def row(name, path, value):
        rows.append((name, path, value))
        print(f"  {name:<34} {path:<36} {value:>14,.0f}", flush=True)

    stack = lambda: gym.make(name, blocks=args.blocks)  # noqa: E731
    print(f"  {args.blocks} blocks, {args.view} view")
    print(f"  {'environment':<34} {'path':<36} {'env-steps/s':>14}")
    row(name, "gymnasium.make, 1 env", single(stack, s))
    row(name, "SyncVectorEnv, 64 envs", sync(stack, 64, s))
    sizes = [64, 256, 1024] if args.quick else [64, 256, 1024, 4096]
    for num_envs in sizes:
        for threads in (1, 2):
            row(name, f"StackVectorEnv, {num_envs} envs, {threads} thr", native(num_envs, threads, s, **world))
    if not args.quick:
        row(f"{name} (grid backend)", "StackVectorEnv, 4096 envs, 2 thr", native(4096, 2, s, backend="grid", **world))
    if not args.quick and not side:
        peers = [("FrozenLake-v1", lambda: gym.make("FrozenLake-v1"))]
        try:
            import minigrid  # noqa: F401  (registers MiniGrid-*)

            peers.insert(0, ("MiniGrid-Empty-8x8-v0", lambda: gym.make("MiniGrid-Empty-8x8-v0")))
        except ImportError:
            print("  (MiniGrid is not installed: pip install minigrid)")
        for peer, make in peers:
            row(peer, "gymnasium.make, 1 env", single(make, s))
            row(peer, "SyncVectorEnv, 64 envs", sync(make, 64, s))
    values = {(n, p): v for n, p, v in rows}
    one = values.get((name, "StackVectorEnv, 4096 envs, 1 thr"))
    two = values.get((name, "StackVectorEnv, 4096 envs, 2 thr"))
    minigrid_single = values.get(("MiniGrid-Empty-8x8-v0", "gymnasium.make, 1 env"))
    if one and two:
        print(f"\n  4096 envs, 2 threads / 1 thread: {two / one:.2f}x")
    if two and minigrid_single:
        print(f"  4096 envs, 2 threads / MiniGrid single env: {two / minigrid_single:,.0f}x")


if __name__ == "__main__":
    main()
