"""Quick start: blockstack through gymnasium.make, a random agent and the exact expert.

    pip install gymnasium numpy  # and the blockstack wheel (see the README)
    python examples/python/quickstart.py

Plays 20 episodes of 3 blocks with random legal actions and the same 20 starts with the
exact solver's actions (``env.unwrapped.expert_action()``), and prints successes and mean
steps. Its output here (commit of 2026-12-01, 2 shared cores):

          random: 1/20 reached the goal, mean 985.0 steps per episode
    exact expert: 20/20 reached the goal, mean 9.6 steps per episode
    took 0.67 s
"""

import time

import gymnasium as gym
import numpy as np

import blockstack  # noqa: F401  (registers blockstack/Stack-v0)


def main():
    start = time.perf_counter()
    env = gym.make("blockstack/Stack-v0", blocks=3, goal="1,0,2", obs="planes", reward="sparse")
    rng = np.random.default_rng(0)
    seeds = [blockstack.episode_seed(1, k) for k in range(20)]

    def random_legal(env, info):
        return int(rng.choice(np.flatnonzero(info["action_mask"])))

    def expert(env, info):
        return env.unwrapped.expert_action()

    for name, choose in (("random", random_legal), ("exact expert", expert)):
        lengths, successes = [], 0
        for seed in seeds:
            obs, info = env.reset(seed=seed)
            for t in range(1, 10_000):
                obs, reward, terminated, truncated, info = env.step(choose(env, info))
                if terminated or truncated:
                    successes += int(terminated)
                    lengths.append(t)
                    break
        print(f"{name:>12}: {successes}/{len(seeds)} reached the goal, mean {np.mean(lengths):.1f} steps per episode")
    print(f"took {time.perf_counter() - start:.2f} s")


if __name__ == "__main__":
    main()
