"""Recordings exported as a Minari dataset (``blockstack.to_minari``): every episode's
observations, actions and flags as recorded, who chose each step and when, the env spec,
the reference scores, withdrawn participants left out, and nothing lossy in between."""

import json

import numpy as np
import pytest

import blockstack

minari = pytest.importorskip("minari", reason="Minari is not installed (pip install 'minari[hdf5]')")


@pytest.fixture()
def datasets(tmp_path, monkeypatch):
    """Minari's datasets folder, in the test's scratch folder."""
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path / "datasets"))
    return tmp_path / "datasets"


@pytest.fixture()
def corrected(cli, tmp_path):
    """A recording of a simulated demonstrator correcting a model (``blockstack correct``),
    and the same recording as a person's session in the terminal writes it (``demo``:
    version 3, a time on every step)."""
    model = tmp_path / "m.safetensors"
    cli("train", "--games", "200", "--goals", "0,1,2:2,1,0", "--out", model)
    record = tmp_path / "correct.jsonl"
    cli("correct", "--model", model, "--demonstrator", "2", "--demos", "3", "--goals", "0,1,2:2,1,0",
        "--out", tmp_path / "c.safetensors", "--record", record)
    timed = tmp_path / "demo.jsonl"
    rows = [json.loads(line) for line in record.read_text().splitlines()]
    t = 0
    for row in rows:
        if row["type"] == "step":
            t += 350
            row["t_ms"], row["received_ms"] = t, 1_764_800_000_000 + t
    timed.write_text("".join(json.dumps(r) + "\n" for r in rows))
    return record, timed


def test_an_exported_dataset_holds_every_episode_as_recorded(corrected, datasets):
    record, timed = corrected
    recorded = blockstack._native.recording_episodes(str(timed), "planes")["episodes"]
    dataset = blockstack.to_minari([timed], "blockstack/stack/test-v0", reference_episodes=5)
    assert isinstance(dataset, minari.MinariDataset)
    loaded = minari.load_dataset("blockstack/stack/test-v0")
    assert loaded.total_episodes == len(recorded) == 3
    for e, r in zip(loaded.iterate_episodes(), recorded):
        assert e.observations.shape == (len(r["actions"]) + 1, 7, 7, 4)
        np.testing.assert_array_equal(e.observations, r["observations"])
        np.testing.assert_array_equal(e.actions, r["actions"])
        np.testing.assert_array_equal(e.rewards, r["rewards"])
        np.testing.assert_array_equal(e.terminations, r["terminations"])
        np.testing.assert_array_equal(e.truncations, r["truncations"])
        np.testing.assert_array_equal(e.infos["person"][1:], r["person"].astype(np.int8))
        np.testing.assert_array_equal(e.infos["t_ms"][1:], r["t_ms"])
        # The first observation is the start: the planes of the recorded start state.
        assert e.observations[0].sum() == 3
    # Who chose: the simulated demonstrator corrected some steps and let the agent take others.
    person = np.concatenate([e.infos["person"][1:] for e in loaded.iterate_episodes()])
    assert 0 < person.sum() < len(person)
    # The env spec makes the recordings' world, and the reference scores bracket play.
    env = loaded.recover_environment()
    assert env.spec.id == "blockstack/Stack-v0"
    assert env.spec.kwargs["blocks"] == 3 and env.spec.kwargs["obs"] == "planes"
    obs, _ = env.reset(seed=1)
    assert obs.shape == (7, 7, 4)
    meta = loaded.storage.metadata
    # Random play against the exact solver's plans (under the paper's reward, which pays
    # for pairs in place every step, random play's long episodes can score higher).
    assert np.isfinite(meta["ref_min_score"]) and np.isfinite(meta["ref_max_score"])
    assert meta["ref_min_score"] != meta["ref_max_score"]
    assert list(meta["requirements"]) == ["blockstack"]
    assert "blockstack" in str(meta["author"])
    assert "infos['person']" in meta["description"]
    # An untimed recording (a simulated demonstrator's) says so: -1.
    untimed = blockstack.to_minari(record, "blockstack/stack/untimed-v0", reference_episodes=2)
    assert all((e.infos["t_ms"][1:] == -1).all() for e in untimed.iterate_episodes())


def test_image_observations_are_stored_exactly_not_jpeg_encoded(corrected, datasets):
    # Minari's HDF5 writer JPEG-encodes uint8 observations it takes for images (at least
    # 32 x 32, values 0 to 255): the paper's screen would come back changed, silently.
    _, timed = corrected
    recorded = blockstack._native.recording_episodes(str(timed), "paper-screen")["episodes"]
    blockstack.to_minari(timed, "blockstack/stack/screen-v0", obs="paper-screen", reference_episodes=2)
    loaded = minari.load_dataset("blockstack/stack/screen-v0")
    for e, r in zip(loaded.iterate_episodes(), recorded):
        assert e.observations.dtype == np.uint8 and e.observations.shape[1:] == (100, 100, 3)
        np.testing.assert_array_equal(e.observations, r["observations"])


def test_withdrawn_participants_are_left_out(corrected, datasets, tmp_path):
    record, timed = corrected
    withdrawn = tmp_path / "withdrawn.jsonl"
    withdrawn.write_text(timed.read_text() + '{"type":"withdrawn","at_ms":1764800009999}\n')
    with pytest.warns(UserWarning, match=f"left out 1 withdrawn participants' recordings: {withdrawn}"):
        dataset = blockstack.to_minari([record, withdrawn], "blockstack/stack/kept-v0", reference_episodes=2)
    assert dataset.total_episodes == 3
    assert "1 withdrawn" in dataset.storage.metadata["description"]
    # Given only withdrawn recordings: refused, naming the withdrawal.
    with pytest.warns(UserWarning), pytest.raises(ValueError, match="withdrawn participant's"):
        blockstack.to_minari([withdrawn], "blockstack/stack/none-v0", reference_episodes=2)
    # An audit reads them, and says so.
    with pytest.warns(UserWarning, match="for an audit"):
        audit = blockstack.to_minari(
            [withdrawn], "blockstack/stack/audit-v0", reference_episodes=2, include_withdrawn=True
        )
    assert audit.total_episodes == 3


def test_read_recording_leaves_a_withdrawn_participant_out_and_checks_the_profile(corrected, tmp_path):
    record, timed = corrected
    withdrawn = tmp_path / "withdrawn.jsonl"
    withdrawn.write_text(timed.read_text() + '{"type":"withdrawn","at_ms":1764800009999}\n')
    with pytest.raises(ValueError, match="withdrew from the study"):
        blockstack.read_recording(withdrawn)
    with pytest.warns(UserWarning, match="for an audit"):
        audited = blockstack.read_recording(withdrawn, include_withdrawn=True)
    assert len(audited["actions"]) == len(blockstack.read_recording(timed)["actions"]) > 0
    # The recording names its protocol (free, the spec profile's): the original profile's
    # run refuses it, naming both.
    assert len(blockstack.read_recording(record, profile="spec")["actions"]) > 0
    with pytest.raises(ValueError, match="the free protocol; this run is of the paper protocol"):
        blockstack.read_recording(record, profile="original")


@pytest.mark.parametrize(
    "bad",
    ["../../escape-v0", "blockstack/../../../esc-v0", "/abs/path-v0", "blockstack/stack/no-version", "a//b-v0", "./x-v0"],
)
def test_an_id_that_would_leave_the_datasets_folder_is_refused_before_anything_is_written(
    bad, corrected, datasets, tmp_path
):
    record, _ = corrected
    before = sorted(p.name for p in tmp_path.iterdir())
    with pytest.raises(ValueError, match="not one blockstack writes"):
        blockstack.to_minari([record], bad, reference_episodes=2)
    assert sorted(p.name for p in tmp_path.iterdir()) == before
    assert not datasets.exists() or list(datasets.rglob("*")) == []


def test_a_failed_export_leaves_nothing_and_the_id_stays_free(corrected, datasets, monkeypatch):
    record, _ = corrected
    real = minari.create_dataset_from_buffers

    def fails_midway(**kwargs):
        real(**kwargs)  # the dataset written in full, then a failure before it is complete
        raise OSError("disk full")

    monkeypatch.setattr(minari, "create_dataset_from_buffers", fails_midway)
    with pytest.raises(OSError, match="disk full"):
        blockstack.to_minari([record], "blockstack/stack/retry-v0", reference_episodes=2)
    assert [p for p in datasets.rglob("*")] == [], "nothing left behind, not even a staging folder"
    monkeypatch.setattr(minari, "create_dataset_from_buffers", real)
    dataset = blockstack.to_minari([record], "blockstack/stack/retry-v0", reference_episodes=2)
    assert dataset.total_episodes == 3
    assert minari.load_dataset("blockstack/stack/retry-v0").total_episodes == 3
    with pytest.raises(ValueError, match="exists already"):
        blockstack.to_minari([record], "blockstack/stack/retry-v0", reference_episodes=2)


def test_recordings_of_two_worlds_name_both_files_and_an_old_one_is_given_its_world(corrected, datasets, tmp_path):
    record, _ = corrected
    rows = [json.loads(line) for line in record.read_text().splitlines()]
    # The same episodes, but a session line that says another horizon: another world.
    other = tmp_path / "other.jsonl"
    other.write_text("".join(
        json.dumps(dict(r, world=dict(r["world"], horizon=r["world"]["horizon"] + 1)) if r["type"] == "session" else
                   r) + "\n" for r in rows))
    with pytest.raises(ValueError, match="is of another world than") as refused:
        blockstack.to_minari([record, other], "blockstack/stack/two-worlds-v0")
    assert str(other) in str(refused.value) and str(record) in str(refused.value)
    assert not (datasets / "blockstack" / "stack" / "two-worlds-v0").exists()
    # A version-2 recording does not say its world: refused without world=, and exported with
    # the world given, whose reward the recovered environment plays.
    old = tmp_path / "old.jsonl"
    session = {k: v for k, v in rows[0].items() if k != "world"}
    old.write_text("".join(json.dumps(r) + "\n" for r in [dict(session, version=2), *rows[1:]]))
    with pytest.raises(ValueError, match="version 1 or 2"):
        blockstack.to_minari(old, "blockstack/stack/old-v0")
    dataset = blockstack.to_minari(old, "blockstack/stack/old-v0", world=rows[0]["world"])
    assert dataset.recover_environment().spec.kwargs["reward"] == rows[0]["world"]["reward"]
