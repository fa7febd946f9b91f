"""`blockstack serve` in a real browser: headless Chromium (Debian's package) driven by
Playwright. Opens the page, plays an episode with key presses and clicks, corrects an
agent, watches it, checks the recording on disk line by line against what was pressed, and
saves a screenshot of each mode as serve-*.png: into target/browser-shots, or into the folder
``BLOCKSTACK_SCREENSHOTS`` names (``BLOCKSTACK_SCREENSHOTS=docs/img`` refreshes the
pictures the docs show; a plain test run leaves the checkout as it was).

Skipped, with the reason, when Playwright or /usr/bin/chromium is absent. Run with
``pytest tests/browser`` after ``cargo build --release`` (scripts/test does both).
"""

import json
import re
import subprocess

import pytest

from browser import BINARY, CHROMIUM, SHOTS, action_name, run, start_server, view, wait_until, wait_view

pytest.importorskip("playwright.sync_api", reason="Playwright is not installed (pip install playwright)")
if not CHROMIUM.exists():
    pytest.skip(f"{CHROMIUM} is absent (apt-get install chromium)", allow_module_level=True)


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    """A server on a free loopback port with a small trained tabular model; its links and
    recording folder."""
    tmp = tmp_path_factory.mktemp("serve")
    model = tmp / "agent.safetensors"
    run("train", "--games", "300", "--out", model)
    record = tmp / "recordings"
    proc, links = start_server("--model", model, "--goals", "0,1,2:2,1,0", "--record-dir", record)
    yield links, record, model
    proc.terminate()
    proc.wait()


def wait_steps(page, steps, episode=None):
    condition = f"view.steps === {steps}"
    if episode is not None:
        condition += f" && view.episode === {episode}"
    wait_view(page, condition)


def click_cell(page, x, y):
    """Clicks the centre of cell (x, y) of the world (y up)."""
    v = view(page)
    cell = 56
    box = page.locator("#world").bounding_box()
    page.mouse.click(box["x"] + (x + 0.5) * cell, box["y"] + (v["grid"][1] - 1 - y + 0.5) * cell)


def recording(record):
    files = sorted(record.iterdir())
    assert len(files) == 1, files
    return [json.loads(line) for line in files[0].read_text().splitlines()]


def test_play_correct_and_watch_in_the_browser(server, page):
    links, record, model = server
    page.goto(links["participants"])
    page.fill("#name", "tester")
    page.click("#begin")
    # #begin navigates to the session's own page, /s/<token>: wait for it to load first.
    page.wait_for_url(re.compile(r"/s/\w+$"), wait_until="load", timeout=10_000)
    wait_view(page)
    v = view(page)
    assert v["mode"] == "play" and v["modes"] == ["play", "watch", "correct"]
    # The colours are sim::render's palette: block 0 red.
    assert v["colours"][0] == "#dc322f"

    # Play: the exact solver's plan, by clicks on blocks, arrow keys and clicks beside the
    # held block, and d to drop.
    start = ";".join(f"{x},{y}" for x, y in v["blocks"])
    goal = ",".join(map(str, v["goal"]))
    plan = json.loads(run("solve", "--start", start, "--goal", goal, "--json"))["actions"]
    pressed = []
    for i, a in enumerate(plan):
        name = action_name(a)
        if name.startswith("pick"):
            x, y = view(page)["blocks"][a - 5]
            click_cell(page, x, y)
        elif name == "drop":
            page.keyboard.press("d")
        elif i % 2 == 0:
            page.keyboard.press({"up": "ArrowUp", "down": "ArrowDown", "left": "ArrowLeft", "right": "ArrowRight"}[name])
        else:
            v = view(page)
            x, y = v["blocks"][v["held"]]
            dx, dy = {"up": (0, 1), "down": (0, -1), "left": (-1, 0), "right": (1, 0)}[name]
            click_cell(page, x + dx, y + dy)
        pressed.append(name)
        wait_steps(page, i + 1)
    v = view(page)
    assert v["over"] and v["outcome"] == "goal"
    assert v["shortest"] == len(plan)
    status = page.inner_text("#status")
    assert f"shortest plan: {len(plan)}" in status
    assert "Goal reached" in page.inner_text("#message")
    SHOTS.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=str(SHOTS / "serve-play.png"))

    # A key that names no block is refused on the page, and nothing changes.
    page.keyboard.press("ArrowUp")
    wait_until(page, "document.getElementById('error').textContent.length > 0")
    assert "episode is over" in page.inner_text("#error")

    # Correct: accept the agent's proposal twice (Enter, then the button), then override
    # with a pick (a key) and a move (a button).
    page.click("#modes button[data-mode=correct]")
    wait_view(page, "view.mode === 'correct'")
    expected = []
    episode = view(page)["episode"]
    for k, how in enumerate(["Enter", "#accept", "2", "#moves button[data-act=right]"]):
        v = view(page)
        proposal = v["proposal"]
        if how == "Enter":
            page.keyboard.press("Enter")
            expected.append((proposal, proposal, False))
        elif how == "#accept":
            page.click("#accept")
            expected.append((proposal, proposal, False))
        elif how == "2":
            page.keyboard.press("2")
            if v["held"] == 2:
                # The held block picked again changes nothing: pick another.
                page.keyboard.press("1")
                expected.append((proposal, "pick 1", True))
            else:
                expected.append((proposal, "pick 2", True))
        else:
            page.click(how)
            expected.append((proposal, "right", True))
        wait_steps(page, k + 1, episode)
    assert page.locator("#qvalues tbody tr").count() > 0
    page.screenshot(path=str(SHOTS / "serve-correct.png"))

    # Watch: the agent runs at the chosen pace; its greedy choice is highlighted.
    page.click("#modes button[data-mode=watch]")
    wait_view(page, "view.mode === 'watch'")
    page.fill("#pace", "6")
    page.click("#run")
    wait_view(page, "view.steps >= 3")
    page.click("#run")
    assert page.locator("#qvalues tr.greedy").count() == 1
    page.screenshot(path=str(SHOTS / "serve-watch.png"))

    # The recording, line by line: the play episode's steps are what was pressed, the
    # correct episode's the proposals accepted and the overrides.
    lines = recording(record)
    assert lines[0]["type"] == "session" and lines[0]["version"] == 4
    episodes = [line for line in lines if line["type"] == "episode"]
    steps = [line for line in lines if line["type"] == "step"]
    assert [e["episode"] for e in episodes] == [0, 1]
    play = [s for s in steps if s["episode"] == 0]
    assert [s["action"] for s in play] == pressed
    assert all(s["correction"] for s in play)
    assert [s["step"] for s in play] == list(range(1, len(plan) + 1))
    correct = [(s["proposed"], s["action"], s["correction"]) for s in steps if s["episode"] == 1]
    assert correct == expected

    # learn-from-demos replays it, unchanged, into the model the session started from.
    out = run(
        "learn-from-demos", next(record.iterdir()), "--model", model, "--out", record.parent / "learnt.safetensors",
        "--on-bad-line", "fail",
    )
    assert f"{len(steps)} steps" in out, out
    # And Python's reader, when the package is installed (scripts/test installs it).
    try:
        import blockstack
    except ImportError:
        return
    arrays = blockstack.read_recording(next(record.iterdir()))
    assert len(arrays["actions"]) == len(steps)


def test_results_page_lists_the_sessions(server, page):
    links, _, _ = server
    page.goto(links["researcher"])
    wait_until(page, "document.querySelectorAll('#sessions tbody tr').length > 0", timeout=10_000)
    row = page.inner_text("#sessions tbody tr")
    assert "tester" in row
    page.screenshot(path=str(SHOTS / "serve-results.png"))
    # A wrong token opens nothing.
    page.goto(re.sub(r"/results/\w+", "/results/" + "0" * 32, links["researcher"]))
    assert "unknown results link" in page.content()


def test_a_training_runs_curve_is_live(page, tmp_path):
    proc = subprocess.Popen(
        [str(BINARY), "train", "--games", "100000", "--serve", "0", "--out", tmp_path / "m.safetensors"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        url = None
        while url is None:
            line = proc.stderr.readline()
            assert line, "train ended before serving its curve"
            if line.startswith("learning curve: "):
                url = line.split(": ", 1)[1].strip()
        page.goto(url)
        wait_until(page, "document.getElementById('curvenote').textContent.includes(' of 100000 games')", timeout=20_000)
        page.wait_for_timeout(1500)
        assert "blockstack train" in page.inner_text("#curvetitle")
        page.screenshot(path=str(SHOTS / "serve-curve.png"))
    finally:
        proc.kill()
        proc.wait()
