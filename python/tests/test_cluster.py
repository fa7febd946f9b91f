"""A sweep on a Ray cluster of three nodes on this machine (a head without CPUs, two workers
of one CPU) that loses a worker once the first checkpoints exist: every run ends once, and
the runs the lost node was training go on from their checkpoints on the node that replaces
it, ending with the network files runs that never stopped end with."""

import csv
import glob
import json
import os
import subprocess
import sys
import time

import pytest

import blockstack
from blockstack import sweep

#: Four DQN runs of a few CPU-seconds each, checkpointed every 1,000 steps.
CONFIG = {
    "train": {
        "command": "dqn",
        "preset": "dqn-planes",
        "blocks": 2,
        "goals": "0,1",
        "steps": 12000,
        "hidden": 64,
        "checkpoint_every": 1000,
    },
    "sweep": {"seed": [1, 2, 3, 4]},
}


def checkpoints(storage):
    return glob.glob(os.path.join(storage, "*", "checkpoint.safetensors"))


def test_a_sweep_survives_the_loss_of_a_node(tmp_path):
    pytest.importorskip("ray")
    from ray.cluster_utils import Cluster

    config = tmp_path / "sweep.json"
    config.write_text(json.dumps(CONFIG))
    out, storage = tmp_path / "results.csv", tmp_path / "runs"
    # Only the processes of this cluster are started and ended here (never `ray stop`).
    cluster = Cluster(initialize_head=True, head_node_args={"num_cpus": 0})
    try:
        lost = cluster.add_node(num_cpus=1)
        cluster.add_node(num_cpus=1)
        cluster.wait_for_nodes()
        driver = subprocess.Popen(
            [sys.executable, "-m", "blockstack.sweep", str(config), "--address", cluster.address,
             "--out", str(out), "--storage", str(storage)],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        )
        # Both running runs have written a checkpoint: the lost node's run has one to go on from.
        clock = time.monotonic()
        while len(checkpoints(storage)) < 2:
            assert driver.poll() is None, "the sweep ended before a node was lost: " + driver.communicate()[1]
            assert time.monotonic() - clock < 180, "no checkpoints after 3 minutes"
            time.sleep(0.1)
        cluster.remove_node(lost)
        cluster.add_node(num_cpus=1)
        stdout, stderr = driver.communicate(timeout=300)
    finally:
        cluster.shutdown()
    assert driver.returncode == 0, stderr

    rows = list(csv.DictReader(out.open()))
    assert sorted(int(r["seed"]) for r in rows) == [1, 2, 3, 4], "every run ends, once"
    assert len({r["run"] for r in rows}) == 4
    progress = [line for line in stdout.splitlines() if line.startswith("[")]
    assert len(progress) == 4, stdout
    resumed = [r for r in rows if int(r["resumed_at"]) > 0]
    assert resumed, f"no run was taken up from a checkpoint: {rows}"
    runs = {sweep.run_name("dqn", flags): flags for flags in sweep.runs(sweep.read_config(str(config)))}
    for row in resumed:
        # It went on from a checkpoint, not from the start, and ended where it should.
        assert int(row["resumed_at"]) % 1000 == 0 and int(row["steps"]) == 12000, row
        undisturbed = tmp_path / f"undisturbed-{row['run']}.safetensors"
        flags = {k: v for k, v in runs[row["run"]].items() if k != "checkpoint_every"}
        blockstack.train_dqn(**flags, out=str(undisturbed))
        model = storage / row["run"] / "model.safetensors"
        assert model.read_bytes() == undisturbed.read_bytes(), f"run {row['run']} differs from an undisturbed run"
