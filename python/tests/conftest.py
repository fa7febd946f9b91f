"""Shared helpers: the CLI binary the Python results are checked against."""

import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def cli():
    """Runs the ``blockstack`` binary (``BLOCKSTACK_BIN``, or the workspace's release build)."""
    binary = pathlib.Path(os.environ.get("BLOCKSTACK_BIN", ROOT / "target" / "release" / "blockstack"))
    if not binary.exists():
        pytest.fail(f"{binary} is missing: build it with `cargo build --release` (scripts/test does)")

    def run(*args):
        return subprocess.run([str(binary), *map(str, args)], check=True, capture_output=True, text=True).stdout

    return run
