"""A sweep's wall time on Ray clusters made on this machine, and what losing a node costs.

    python python/benchmarks/cluster.py [--runs 4] [--steps 12000] [--out cluster.json]

The same sweep of ``--runs`` DQN runs (``dqn-planes`` on 2 blocks, ``--steps`` steps each,
checkpointed every tenth of them) three times, on clusters of Ray's testing tool
(``ray.cluster_utils.Cluster``: a head without CPUs, workers of one CPU each): (a) one worker;
(b) two workers; (c) two workers, one removed once two runs have written a checkpoint, and a
fresh one added. Prints one line per cluster: the driver's wall time, and for (c) the runs
taken up from a checkpoint and the steps each had done then; then what the loss cost, (c)
minus (b). Writes the figures as JSON to ``--out``. Each sweep's runs get a folder of their
own, so none reads another's results. Only the processes of these clusters are started and
ended (never ``ray stop``).

On a machine of two cores, two one-CPU workers use both: (b) against (a) is the speed-up of
a second node; the head and the driver take a little CPU of their own.
"""

from __future__ import annotations

import argparse
import csv
import glob
import json
import os
import subprocess
import sys
import tempfile
import time

from ray.cluster_utils import Cluster


def sweep(folder: str, runs: int, steps: int, workers: int, lose: bool) -> dict:
    config = os.path.join(folder, "sweep.json")
    with open(config, "w") as f:
        json.dump({
            "train": {"command": "dqn", "preset": "dqn-planes", "blocks": 2, "goals": "0,1", "steps": steps,
                      "hidden": 64, "checkpoint_every": steps // 10},
            "sweep": {"seed": list(range(1, runs + 1))},
        }, f)
    out, storage = os.path.join(folder, "results.csv"), os.path.join(folder, "runs")
    cluster = Cluster(initialize_head=True, head_node_args={"num_cpus": 0})
    try:
        nodes = [cluster.add_node(num_cpus=1) for _ in range(workers)]
        cluster.wait_for_nodes()
        start = time.monotonic()
        driver = subprocess.Popen(
            [sys.executable, "-m", "blockstack.sweep", config, "--address", cluster.address,
             "--out", out, "--storage", storage],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        )
        lost_at = None
        if lose:
            while len(glob.glob(os.path.join(storage, "*", "checkpoint.safetensors"))) < 2:
                if driver.poll() is not None:
                    raise SystemExit("the sweep ended before a node was lost: " + driver.communicate()[1])
                time.sleep(0.1)
            lost_at = time.monotonic() - start
            cluster.remove_node(nodes[0])
            cluster.add_node(num_cpus=1)
        _, stderr = driver.communicate()
        seconds = time.monotonic() - start
    finally:
        cluster.shutdown()
    if driver.returncode != 0:
        raise SystemExit(f"the sweep failed: {stderr}")
    rows = list(csv.DictReader(open(out)))
    return {
        "workers": workers,
        "lost_a_node": lose,
        "seconds": round(seconds, 1),
        "node_lost_after_seconds": None if lost_at is None else round(lost_at, 1),
        "runs": len(rows),
        "resumed_at_steps": sorted(int(r["resumed_at"]) for r in rows if int(r["resumed_at"]) > 0),
        "train_seconds": sorted(round(float(r["train_seconds"]), 1) for r in rows),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=4)
    parser.add_argument("--steps", type=int, default=12000)
    parser.add_argument("--out", default="cluster.json")
    args = parser.parse_args()
    results = []
    for workers, lose in [(1, False), (2, False), (2, True)]:
        with tempfile.TemporaryDirectory() as folder:
            r = sweep(folder, args.runs, args.steps, workers, lose)
        results.append(r)
        extra = f", runs taken up at steps {r['resumed_at_steps']}" if lose else ""
        print(f"{args.runs} runs of {args.steps} steps, {workers} worker{'s' if workers > 1 else ''}"
              f"{', one lost' if lose else ''}: {r['seconds']:.1f} s{extra}", flush=True)
    one, two, lost = results
    print(f"a second worker: {one['seconds'] / two['seconds']:.2f}x faster; "
          f"losing one cost {lost['seconds'] - two['seconds']:.1f} s")
    with open(args.out, "w") as f:
        json.dump({"runs": args.runs, "steps": args.steps, "sweeps": results}, f, indent=2)
        f.write("\n")


if __name__ == "__main__":
    main()
