"""``python -m blockstack.reproduce``: the reproduction from Python, E8's arms on Ray giving
the report one machine gives."""

import json

import pytest

from blockstack import reproduce


def figures(folder):
    """A report's results without where it ran (the machine, the threads)."""
    results = json.loads((folder / "results.json").read_text())
    results.pop("ran")
    return results


def test_e8_on_a_local_ray_writes_the_report_of_one_machine(tmp_path, capsys):
    pytest.importorskip("ray")
    here, there = tmp_path / "here", tmp_path / "there"
    assert reproduce.main(["--quick", "--only", "E8", "--seed", "3", "--out", str(here)]) == 0
    assert reproduce.main(["--quick", "--only", "E8", "--seed", "3", "--out", str(there),
                           "--ray", "--num-cpus", "2"]) == 0
    printed = capsys.readouterr().out
    assert "E8: 2 arms sent to Ray" in printed and "E8: 2/2 arms done" in printed, printed
    assert figures(here) == figures(there)
    assert (here / "README.md").read_text() == (there / "README.md").read_text()
    # Each arm's checkpoint, beside the report.
    assert len(list((tmp_path / "there-e8-arms").iterdir())) == 2


def test_bad_settings_are_refused_before_any_work(tmp_path, capsys):
    for argv, message in [
        (["--only", "E11"], "no experiment E11: name experiments E1 to E8"),
        (["--only", "E9"], "E9 is not one of `blockstack reproduce`'s experiments (E1 to E8): run `blockstack benchmark --only E9`"),
        (["--jobs", "0"], "--jobs must be at least 1"),
        (["--out", str(tmp_path / "a-file" / "report")], "a-file"),
    ]:
        (tmp_path / "a-file").write_text("")
        assert reproduce.main(argv + ([] if "--out" in argv else ["--out", str(tmp_path / "r")])) == 2
        assert message in capsys.readouterr().err


def test_e8_arms_are_sent_costliest_first():
    # At the long budget the arm on the paper's screen, about an hour of one core, goes
    # first; every arm is sent once.
    from blockstack import _native
    names = _native.e8_arms(long=True)
    start = _native.e8_start_order(long=True)
    assert sorted(start) == list(range(len(names)))
    assert names[start[0]] == "ours on the paper's screen: DQfD, conv network, 3 blocks"
