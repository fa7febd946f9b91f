"""MaskablePPO (sb3-contrib) learning to stack 2 blocks from ``planes`` with the action mask.

    pip install torch sb3-contrib gymnasium numpy  # and the blockstack wheel (see the README)
    python examples/python/maskable_ppo.py [--steps 200000]

Trains on ``blockstack/Stack-v0`` (2 blocks, goal ``1,0``, ``planes``, the ``dense``
reward, episodes cut at 100 steps) with the mask from ``env.action_masks()`` (which
MaskablePPO asks every environment for), then plays the policy deterministically from 200
seeded starts and reports successes and steps against the shortest plan. Its output here
(torch 2.15 and sb3-contrib 2.9.2 on CPU, 2 cores shared with other builds; 11 min 18 s
wall in all):

    after 200000 steps (671 s): 175/200 reached the goal, mean steps 1.452x the shortest plan

In the ``spec`` world every action is legal, so the mask is all ones and changes nothing;
with a restricting protocol the same code masks out the illegal actions.
"""

import argparse
import time

import gymnasium as gym
import numpy as np
from sb3_contrib import MaskablePPO
from stable_baselines3.common.env_util import make_vec_env

import blockstack

KWARGS = {"blocks": 2, "goal": "1,0", "obs": "planes", "reward": "dense", "horizon": 100}


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--steps", type=int, default=200_000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--profile", default="spec", help="spec, or original (the paper's protocol: a real mask)")
    args = parser.parse_args()
    kwargs = dict(KWARGS, profile=args.profile)
    clock = time.perf_counter()
    envs = make_vec_env("blockstack/Stack-v0", n_envs=8, seed=args.seed, env_kwargs=kwargs)
    # The planes are 0/1, not image bytes: no scaling by 255.
    model = MaskablePPO("MlpPolicy", envs, seed=args.seed, n_steps=256, batch_size=256, gamma=0.99,
                        policy_kwargs={"normalize_images": False}, verbose=0)
    model.learn(total_timesteps=args.steps)
    train_seconds = time.perf_counter() - clock

    env = gym.make("blockstack/Stack-v0", **kwargs)
    successes, ratios = 0, []
    for k in range(200):
        obs, info = env.reset(seed=blockstack.episode_seed(args.seed + 1000, k))
        optimum = env.unwrapped.optimal_steps()
        for t in range(1, 101):
            action, _ = model.predict(obs, deterministic=True, action_masks=env.unwrapped.action_masks())
            obs, reward, terminated, truncated, info = env.step(int(action))
            if terminated or truncated:
                break
        if terminated:
            successes += 1
            ratios.append(t / optimum)
    mean_ratio = f"{np.mean(ratios):.3f}x" if ratios else "-"
    print(f"after {args.steps} steps ({train_seconds:.0f} s): {successes}/200 reached the goal, "
          f"mean steps {mean_ratio} the shortest plan")


if __name__ == "__main__":
    main()
