"""Trains d3rlpy's DiscreteBC for a few steps on a Minari dataset that
``blockstack.to_minari`` wrote, and saves what it saw: run by the interpreter of
d3rlpy's own virtualenv (d3rlpy pins its own gymnasium; see docs/serve.md, "Offline
learners: a Minari dataset"), not the package's.

    python d3rlpy_check.py DATASET_ID OUT.npz

The ``MDPDataset`` is built here from Minari's episodes, each observation flattened to a
vector: d3rlpy's own Minari loader concatenates the T + 1 observations with the T actions,
and would shift them by one. The episodes d3rlpy holds after building are saved (their
observations and actions), so that the caller compares them with the recordings.
"""

import sys

import numpy as np


def main(dataset_id: str, out: str) -> None:
    import d3rlpy
    import minari

    dataset = minari.load_dataset(dataset_id)
    observations, actions, rewards, terminals, timeouts = [], [], [], [], []
    for e in dataset.iterate_episodes():
        steps = len(e.actions)
        # T + 1 observations: the last one, after the last action, has no action of its own.
        observations.append(e.observations[:steps].reshape(steps, -1).astype(np.float32))
        actions.append(np.asarray(e.actions).reshape(steps, 1))
        rewards.append(np.asarray(e.rewards, dtype=np.float32).reshape(steps, 1))
        terminals.append(np.asarray(e.terminations, dtype=np.float32))
        # d3rlpy ends an episode at a terminal or a timeout: the last step of each is one.
        timeout = np.asarray(e.truncations, dtype=np.float32)
        if not (terminals[-1][-1] or timeout[-1]):
            timeout[-1] = 1.0
        timeouts.append(timeout)
    mdp = d3rlpy.dataset.MDPDataset(
        observations=np.concatenate(observations),
        actions=np.concatenate(actions),
        rewards=np.concatenate(rewards),
        terminals=np.concatenate(terminals),
        timeouts=np.concatenate(timeouts),
        action_space=d3rlpy.ActionSpace.DISCRETE,
        action_size=int(dataset.action_space.n),
    )
    bc = d3rlpy.algos.DiscreteBCConfig(batch_size=32).create(device="cpu:0")
    # No logger: d3rlpy's default writes a d3rlpy_logs folder into the working directory.
    bc.fit(
        mdp,
        n_steps=20,
        n_steps_per_epoch=20,
        show_progress=False,
        save_interval=10**9,
        logger_adapter=d3rlpy.logging.NoopAdapterFactory(),
    )
    seen = {}
    for k, episode in enumerate(mdp.episodes):
        seen[f"observations_{k}"] = np.asarray(episode.observations)
        seen[f"actions_{k}"] = np.asarray(episode.actions).reshape(-1)
    greedy = bc.predict(np.concatenate(observations)[:8])
    np.savez(out, episodes=len(mdp.episodes), greedy=greedy, **seen)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
