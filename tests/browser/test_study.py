"""A crowd study in a real browser (headless Chromium, Playwright): participants arrive
from a platform with their ids in the URL, agree to the consent form, read the
instructions, play a top-view episode (correcting the agent) or a side-view one (by block
moves), get the completion code and are sent back to the platform; one comes back and
resumes, one withdraws, one declines. Then the researcher's page, a replay, the CSV, and
the recordings exported as a Minari dataset that d3rlpy trains on. Screenshots go where
test_serve.py's go (study-*.png).

Skipped, with the reason, when Playwright or /usr/bin/chromium is absent; the Minari part
when Minari is not installed, d3rlpy's when its virtualenv is (docs/serve.md, "Offline
learners: a Minari dataset").
"""

import csv
import io
import json
import os
import pathlib
import re
import subprocess

import pytest

from browser import CHROMIUM, ROOT, SHOTS, action_name, run, start_server, view, wait_until, wait_view

pytest.importorskip("playwright.sync_api", reason="Playwright is not installed (pip install playwright)")
if not CHROMIUM.exists():
    pytest.skip(f"{CHROMIUM} is absent (apt-get install chromium)", allow_module_level=True)

PLATFORM = "https://platform.invalid"
CODE = "C7Q2XK"
SIDE_GOAL = "0,1/2"
KEYS = {"up": "ArrowUp", "down": "ArrowDown", "left": "ArrowLeft", "right": "ArrowRight", "drop": "d"}

STUDY = f"""
name = "crowd-test"
seed = 7
consent = \"\"\"
# Consent

You will teach an agent to stack blocks. <script>window.ran = true</script>
\"\"\"
instructions = "Stack the blocks as the **goal** shows."
participant_ids = ["PROLIFIC_PID", "STUDY_ID", "SESSION_ID"]
completion_code = "{CODE}"
completion_url = "{PLATFORM}/complete?cc={CODE}"
withdrawal = "mark"

[[condition]]
name = "top-correct"
view = "top"
model = "top.safetensors"
goals = "0,1,2:2,1,0"
episodes = 1
modes = ["correct", "play"]

[[condition]]
name = "side-play"
view = "side"
model = "side.safetensors"
goals = "{SIDE_GOAL}"
episodes = 1
modes = ["play", "correct"]
"""


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    """The study's server (two small models, one per view): its links and recording folder."""
    tmp = tmp_path_factory.mktemp("study")
    run("train", "--games", "300", "--goals", "0,1,2:2,1,0", "--out", tmp / "top.safetensors")
    run("train", "--view", "side", "--games", "300", "--out", tmp / "side.safetensors")
    (tmp / "study.toml").write_text(STUDY)
    record = tmp / "recordings"
    proc, links = start_server("--study", tmp / "study.toml", "--record-dir", record)
    yield {"links": links, "record": record, "tmp": tmp}
    proc.terminate()
    proc.wait()


def arrive(page, study, pid):
    """A participant from the platform opens the study's link with their ids."""
    page.goto(f"{study['links']['participants']}?PROLIFIC_PID={pid}&STUDY_ID=S1&SESSION_ID=X-{pid}")


def agree_and_begin(page):
    page.wait_for_selector("#consent:not([hidden])")
    page.click("text=I agree")
    page.wait_for_selector("#instructions:not([hidden])")
    page.click("#start")
    # Begin posts the form and lands on the session's own page, /s/<token>.
    page.wait_for_url(re.compile(r"/s/\w+$"), wait_until="load", timeout=10_000)
    wait_view(page)
    return page.url


def cell_point(page, x, y):
    v = view(page)
    box = page.locator("#world").bounding_box()
    return box["x"] + (x + 0.5) * 56, box["y"] + (v["grid"][1] - 1 - y + 0.5) * 56


def finish_and_return(page, study):
    """The end: the completion code, then the platform's completion link."""
    page.wait_for_selector("#end:not([hidden])", timeout=10_000)
    assert page.inner_text("#code") == CODE
    page.wait_for_url(f"{PLATFORM}/complete?cc={CODE}", timeout=10_000)


def test_crowd_participants_consent_play_finish_resume_withdraw_and_decline(study, page):
    # The platform's completion page, answered here (nothing leaves the machine).
    page.route(f"{PLATFORM}/**", lambda route: route.fulfill(body="<p>back on the platform</p>", content_type="text/html"))
    record = study["record"]

    # A: consent (the Markdown's script is shown as text, never run), instructions, then
    # the top view's episode, correcting the agent with the exact solver's plan.
    arrive(page, study, "A1")
    page.wait_for_selector("#consent:not([hidden])")
    assert "<script>" in page.inner_text("#consenttext")
    assert page.evaluate("window.ran") is None
    SHOTS.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=str(SHOTS / "study-consent.png"))
    page.click("text=I agree")
    page.wait_for_selector("#instructions:not([hidden])")
    assert page.inner_html("#instructionstext").count("<strong>goal</strong>") == 1
    page.screenshot(path=str(SHOTS / "study-instructions.png"))
    page.click("#start")
    page.wait_for_url(re.compile(r"/s/\w+$"), wait_until="load", timeout=10_000)
    wait_view(page)
    v = view(page)
    assert (v["condition"], v["mode"], v["view"]) == ("top-correct", "correct", "top")
    start = ";".join(f"{x},{y}" for x, y in v["blocks"])
    plan = json.loads(run("solve", "--start", start, "--goal", ",".join(map(str, v["goal"])), "--json"))["actions"]
    for i, a in enumerate(plan):
        name = action_name(a)
        page.keyboard.press(name[-1] if name.startswith("pick") else KEYS[name])
        wait_view(page, f"view.steps === {i + 1}")
    finish_and_return(page, study)

    # B: the side view, by block moves: a click on a block, then on its destination column.
    arrive(page, study, "B1")
    b_url = agree_and_begin(page)
    v = view(page)
    assert (v["condition"], v["mode"], v["view"]) == ("side-play", "play", "side")
    start = ";".join(f"{x},{y}" for x, y in v["blocks"])
    moves = json.loads(run("solve", "--view", "side", "--start", start, "--goal", SIDE_GOAL, "--json"))["moves"]
    assert moves, "the side view's start is already the goal"
    for k, move in enumerate(moves):
        v = view(page)
        taken = {x for x, _ in v["blocks"]}
        column = v["blocks"][move["onto"]][0] if move["onto"] != "table" else min(set(range(v["grid"][0])) - taken)
        page.mouse.click(*cell_point(page, *v["blocks"][move["block"]]))
        page.mouse.click(*cell_point(page, column, 0))
        wait_view(page, f"view.blocks[{move['block']}][0] === {column} && view.held === null")
        if k == 0:
            page.wait_for_timeout(500)  # the fall's animation ends
            page.screenshot(path=str(SHOTS / "study-side.png"))
    page.wait_for_selector("#end:not([hidden])", timeout=10_000)
    page.screenshot(path=str(SHOTS / "study-end.png"))
    finish_and_return(page, study)
    # B comes back with the same id: the same session, not a new one.
    arrive(page, study, "B1")
    page.wait_for_url(b_url, timeout=10_000)

    # C: agrees, begins (the top view again: the conditions stay balanced), then withdraws;
    # coming back, C is told so.
    arrive(page, study, "C1")
    agree_and_begin(page)
    assert view(page)["condition"] == "top-correct"
    page.keyboard.press("1")
    wait_view(page, "view.steps === 1")
    page.once("dialog", lambda dialog: dialog.accept())
    page.click("#withdraw")
    page.wait_for_selector("#withdrawn:not([hidden])")
    assert "withdrawn" in page.inner_text("#withdrawntext")
    arrive(page, study, "C1")
    page.wait_for_selector("#withdrawn:not([hidden])")

    # D declines: nothing recorded.
    everything = sorted(record.iterdir())
    arrive(page, study, "D1")
    page.wait_for_selector("#consent:not([hidden])")
    page.click("text=I do not agree")
    page.wait_for_selector("#declined:not([hidden])")
    assert sorted(record.iterdir()) == everything
    files = sorted(record.glob("p*.jsonl"))

    # The recordings: three participants with their platform ids, C's marked withdrawn, every
    # step timed.
    assert len(files) == 3, files
    by_id = {}
    for f in files:
        lines = [json.loads(line) for line in f.read_text().splitlines()]
        by_id[lines[0]["participant"]["ids"]["PROLIFIC_PID"]] = (f, lines)
    assert sorted(by_id) == ["A1", "B1", "C1"]
    assert by_id["B1"][1][0]["view"] == "side"
    assert by_id["C1"][1][-1]["type"] == "withdrawn"
    a_steps = [line for line in by_id["A1"][1] if line["type"] == "step"]
    assert [s["action"] for s in a_steps] == [action_name(a) for a in plan]
    assert all(s["correction"] for s in a_steps)
    assert all(isinstance(s["t_ms"], int) and s["t_ms"] >= 0 for s in a_steps)
    assert [s["t_ms"] for s in a_steps] == sorted(s["t_ms"] for s in a_steps)
    study["files"] = {pid: f for pid, (f, _) in by_id.items()}
    study["plan"] = plan


def test_the_researcher_sees_figures_replays_and_the_csv(study, page):
    if "files" not in study:
        pytest.skip("the participants' test did not finish")
    page.goto(study["links"]["researcher"])
    # C withdrew: left out. A's and B's episodes are the table's rows.
    wait_until(page, "document.querySelectorAll('#episodes tbody tr').length === 2", timeout=10_000)
    conditions = page.inner_text("#conditions tbody")
    assert "top-correct" in conditions and "side-play" in conditions
    page.screenshot(path=str(SHOTS / "study-results.png"), full_page=True)

    csv_url = page.evaluate("document.getElementById('csv').href")
    answer = page.request.get(csv_url)
    assert answer.ok
    rows = list(csv.DictReader(io.StringIO(answer.text())))
    assert sorted(r["participant_id"] for r in rows) == ["A1", "B1"]
    a = next(r for r in rows if r["participant_id"] == "A1")
    assert (a["condition"], a["view"], a["success"]) == ("top-correct", "top", "true")
    assert int(a["steps"]) == int(a["optimum"]) == len(study["plan"])
    assert int(a["corrections"]) == len(study["plan"])
    assert int(a["duration_ms"]) >= 0 and a["median_rt_ms"] != ""

    # A replay, step by step.
    page.locator("#episodes tbody tr a").first.click()
    page.wait_for_selector("#replay:not([hidden])", timeout=10_000)
    wait_until(page, "document.getElementById('replaystatus').textContent.length > 0", timeout=10_000)
    before = page.inner_text("#replaystatus")
    page.click("#replaynext")
    wait_until(page, 
        f"document.getElementById('replaystatus').textContent !== {json.dumps(before)}", timeout=10_000
    )
    page.screenshot(path=str(SHOTS / "study-replay.png"))


def test_the_study_exports_to_minari_and_d3rlpy_trains_on_it(study, tmp_path):
    if "files" not in study:
        pytest.skip("the participants' test did not finish")
    blockstack = pytest.importorskip("blockstack", reason="the Python package is not installed (scripts/test installs it)")
    minari = pytest.importorskip("minari", reason="Minari is not installed (pip install 'minari[hdf5]')")
    datasets = tmp_path / "datasets"
    os.environ["MINARI_DATASETS_PATH"] = str(datasets)
    try:
        files = study["files"]
        # The top view's recordings, C's (withdrawn) among them: C is left out.
        dataset = blockstack.to_minari([files["A1"], files["C1"]], "blockstack/stack/crowd-test-v0", reference_episodes=2)
        assert dataset.total_episodes == 1
        episode = next(minari.load_dataset("blockstack/stack/crowd-test-v0").iterate_episodes())
        assert list(episode.actions) == study["plan"]
        assert list(episode.infos["person"][1:]) == [1] * len(study["plan"])
        assert (episode.infos["t_ms"][1:] >= 0).all()
    finally:
        del os.environ["MINARI_DATASETS_PATH"]
    venv = pathlib.Path(os.environ.get("BLOCKSTACK_D3RLPY_VENV", ROOT / "target" / "d3rlpy-venv"))
    if not (venv / "ready").exists():
        pytest.skip(f"{venv} is missing or half made: scripts/d3rlpy-venv makes it")
    out = tmp_path / "seen.npz"
    trained = subprocess.run(
        [str(venv / "bin" / "python"), str(ROOT / "python" / "tests" / "d3rlpy_check.py"), "blockstack/stack/crowd-test-v0", str(out)],
        env=dict(os.environ, MINARI_DATASETS_PATH=str(datasets)),
        capture_output=True,
        text=True,
    )
    assert trained.returncode == 0, trained.stderr
    import numpy as np

    seen = np.load(out)
    assert int(seen["episodes"]) == 1
    np.testing.assert_array_equal(seen["actions_0"], study["plan"])
