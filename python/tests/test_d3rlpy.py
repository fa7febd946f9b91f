"""An offline learner trains on exported recordings: d3rlpy's DiscreteBC, in a
virtualenv of its own (``scripts/d3rlpy-venv`` makes ``target/d3rlpy-venv``: d3rlpy pins
its own gymnasium and needs PyTorch), fits a few steps on a dataset ``to_minari`` wrote,
and the observations and actions it saw equal the recording's, episode by episode.

Skipped, saying why, when that virtualenv is missing (CI does not make it: PyTorch is
hundreds of megabytes even CPU-only).
"""

import json
import os
import pathlib
import subprocess

import numpy as np
import pytest

import blockstack

ROOT = pathlib.Path(__file__).resolve().parents[2]
VENV = pathlib.Path(os.environ.get("BLOCKSTACK_D3RLPY_VENV", ROOT / "target" / "d3rlpy-venv"))
PYTHON = VENV / "bin" / "python"

pytest.importorskip("minari", reason="Minari is not installed (pip install 'minari[hdf5]')")
if not (VENV / "ready").exists():
    pytest.skip(f"{VENV} is missing or half made: scripts/d3rlpy-venv makes it", allow_module_level=True)


def train_on(dataset_id, tmp_path, env):
    """Runs DiscreteBC in d3rlpy's virtualenv; what it saw, per episode."""
    out = tmp_path / "seen.npz"
    run = subprocess.run(
        [str(PYTHON), str(pathlib.Path(__file__).with_name("d3rlpy_check.py")), dataset_id, str(out)],
        env=env,
        capture_output=True,
        text=True,
    )
    assert run.returncode == 0, run.stderr
    return np.load(out)


def test_d3rlpy_trains_on_the_exported_recordings_and_sees_them_as_recorded(cli, tmp_path, monkeypatch):
    datasets = tmp_path / "datasets"
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(datasets))
    model = tmp_path / "m.safetensors"
    cli("train", "--games", "200", "--goals", "0,1,2:2,1,0", "--out", model)
    record = tmp_path / "correct.jsonl"
    cli("correct", "--model", model, "--demonstrator", "1", "--demos", "4", "--goals", "0,1,2:2,1,0",
        "--out", tmp_path / "c.safetensors", "--record", record)
    blockstack.to_minari(record, "blockstack/stack/bc-v0", reference_episodes=2)
    seen = train_on("blockstack/stack/bc-v0", tmp_path, dict(os.environ, MINARI_DATASETS_PATH=str(datasets)))
    recorded = blockstack._native.recording_episodes(str(record), "planes")["episodes"]
    assert int(seen["episodes"]) == len(recorded) == 4
    for k, e in enumerate(recorded):
        steps = len(e["actions"])
        expected = e["observations"][:steps].reshape(steps, -1).astype(np.float32)
        np.testing.assert_array_equal(seen[f"observations_{k}"], expected, err_msg=json.dumps({"episode": k}))
        np.testing.assert_array_equal(seen[f"actions_{k}"], e["actions"])
    assert seen["greedy"].shape == (8,)
