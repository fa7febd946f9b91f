"""A crowd study against a hostile participant, in a real browser (headless Chromium,
Playwright) and by script: a session taken over by someone else's platform id, the
completion code claimed without taking part, and a study closed by scripted joins. Each
case was an open door before the study server kept sessions to their tokens, sent the code
only in a finished participant's last view and counted only participants who acted; each
test here shows the door shut.

Scripted clients join from other loopback addresses (127.0.0.2, 127.0.0.3, ...): to the
server each is another machine, as a crowd of bots would be.
"""

import http.client
import json
import re
import subprocess
import urllib.parse

import pytest

from browser import BINARY, CHROMIUM, CHROMIUM_ARGS, action_name, run, start_server, view, wait_view

pytest.importorskip("playwright.sync_api", reason="Playwright is not installed (pip install playwright)")
if not CHROMIUM.exists():
    pytest.skip(f"{CHROMIUM} is absent (apt-get install chromium)", allow_module_level=True)

CODE = "K3Y9ZQ"
PLATFORM = "https://platform.invalid"
KEYS = {"up": "ArrowUp", "down": "ArrowDown", "left": "ArrowLeft", "right": "ArrowRight", "drop": "d"}

STUDY = f"""
name = "hostile"
seed = 5
max_participants = 3
consent = "# Consent\\n\\nYou agree to be recorded."
instructions = "Stack the blocks."
participant_ids = ["PROLIFIC_PID", "STUDY_ID", "SESSION_ID"]
completion_code = "{CODE}"
completion_url = "{PLATFORM}/complete?cc={CODE}"
withdrawal = "mark"

[[condition]]
name = "top"
goals = "0,1,2"
episodes = 1
modes = ["play"]
"""


@pytest.fixture(scope="module")
def browser():
    playwright = pytest.importorskip("playwright.sync_api")
    with playwright.sync_playwright() as p:
        b = p.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_ARGS)
        yield b
        b.close()


@pytest.fixture
def study(tmp_path):
    """A fresh study server (no model: the untrained stand-in, play mode only): its links,
    address, record folder and a way to start it again on the same folder."""
    (tmp_path / "study.toml").write_text(STUDY)
    record = tmp_path / "recordings"
    state = {"record": record, "procs": []}

    def launch(*extra):
        proc, links = start_server("--study", tmp_path / "study.toml", "--record-dir", record, *extra)
        state["procs"].append(proc)
        state["links"] = links
        parts = urllib.parse.urlsplit(links["participants"])
        state["host"], state["port"] = parts.hostname, parts.port
        return state

    state["launch"] = launch
    yield state
    for proc in state["procs"]:
        proc.terminate()
        proc.wait()


def request(study, method, path, body="", source="127.0.0.1", headers=None):
    """A scripted request from the loopback address `source`: the status, headers and body."""
    conn = http.client.HTTPConnection(study["host"], study["port"], timeout=10, source_address=(source, 0))
    all_headers = {"Content-Type": "application/x-www-form-urlencoded", "Origin": f"http://{study['host']}:{study['port']}"}
    all_headers.update(headers or {})
    conn.request(method, path, body=body, headers=all_headers)
    answer = conn.getresponse()
    result = (answer.status, dict(answer.getheaders()), answer.read().decode())
    conn.close()
    return result


def ids(pid):
    return f"PROLIFIC_PID={pid}&STUDY_ID=S1&SESSION_ID=X-{pid}"


def arrive(page, study, pid):
    page.goto(f"{study['links']['participants']}?{ids(pid)}")


def agree_and_begin(page):
    page.wait_for_selector("#consent:not([hidden])")
    page.click("text=I agree")
    page.wait_for_selector("#instructions:not([hidden])")
    page.click("#start")


def begin_session(page):
    agree_and_begin(page)
    page.wait_for_url(re.compile(r"/s/\w+$"), wait_until="load", timeout=10_000)
    wait_view(page)
    return page.url


def press(page, name):
    page.keyboard.press(name[-1] if name.startswith("pick") else KEYS[name])


def plan_of(v):
    start = ";".join(f"{x},{y}" for x, y in v["blocks"])
    return json.loads(run("solve", "--start", start, "--goal", ",".join(map(str, v["goal"])), "--json"))["actions"]


def lines(path):
    return [json.loads(line) for line in path.read_text().splitlines()]


def test_a_platform_id_opens_no_one_elses_session(study, browser):
    study["launch"]()
    record = study["record"]
    # A takes part in their own browser and plays a step.
    own = browser.new_context()
    a = own.new_page()
    arrive(a, study, "A1")
    a_url = begin_session(a)
    a.keyboard.press("1")
    wait_view(a, "view.steps === 1")
    [a_file] = sorted(record.glob("p*.jsonl"))
    before = a_file.read_text()

    # Someone who knows A's id opens the study's link with it in another browser: the
    # consent form, as for anyone, and after it no way into A's session.
    other = browser.new_context()
    b = other.new_page()
    arrive(b, study, "A1")
    b.wait_for_selector("#consent:not([hidden])", timeout=10_000)
    b.wait_for_timeout(1500)
    assert "/s/" not in b.url
    agree_and_begin(b)
    b.wait_for_load_state("load")
    b.wait_for_timeout(500)
    assert b.url != a_url and "/s/" not in b.url, b.url
    text = b.inner_text("body")
    assert "session" in text and "already" in text, text

    # A script naming A's id learns nothing: the same answer as for an id never seen.
    known = request(study, "POST", "/api/resume", ids("A1"), source="127.0.0.2")
    unknown = request(study, "POST", "/api/resume", ids("Z9"), source="127.0.0.2")
    assert (known[0], known[2]) == (unknown[0], unknown[2]), (known, unknown)
    assert a_url.rsplit("/", 1)[1] not in known[2]

    # A's session and recording are A's alone: nothing was played or withdrawn in them.
    assert a_file.read_text() == before
    assert all(line["type"] != "withdrawn" for line in lines(a_file))

    # A returns in the same browser: their session.
    arrive(a, study, "A1")
    a.wait_for_url(a_url, timeout=10_000)
    wait_view(a, "view.steps === 1")

    # The researcher issues a resume link for A, which opens A's session in a new browser.
    status, _, body = request(
        study, "POST", study["links"]["researcher"].replace("/results/", "/api/results/").split(f":{study['port']}", 1)[1] + "/resume",
        "participant=0",
    )
    assert status == 200, body
    link = json.loads(body)["link"]
    third = browser.new_context().new_page()
    third.goto(link)
    wait_view(third, "view.steps === 1")
    own.close()
    other.close()


def test_the_completion_code_is_earned(study, browser):
    study["launch"]()
    # Nothing a visitor can fetch before the end holds the code.
    for path in ["/api/study", "/", "/assets/app.js", f"/?{ids('C1')}"]:
        status, _, body = request(study, "GET", path)
        assert status == 200, path
        assert CODE not in body, f"{path} gives the completion code away"
    # A script that joins and does nothing is not given it either.
    status, headers, _ = request(study, "POST", "/join", "consent=agree&" + ids("S1"), source="127.0.0.3")
    assert status == 303, status

    # A participant sees it only in the last view, once the episode is done.
    context = browser.new_context()
    page = context.new_page()
    page.route(f"{PLATFORM}/**", lambda route: route.fulfill(body="<p>back</p>", content_type="text/html"))
    arrive(page, study, "C1")
    page.wait_for_selector("#consent:not([hidden])")
    assert CODE not in page.content()
    begin_session(page)
    v = view(page)
    assert CODE not in json.dumps(v) and CODE not in page.content()
    plan = plan_of(v)
    for i, a in enumerate(plan[:-1]):
        press(page, action_name(a))
        wait_view(page, f"view.steps === {i + 1}")
    assert CODE not in json.dumps(view(page)) and CODE not in page.content()
    press(page, action_name(plan[-1]))
    page.wait_for_selector("#end:not([hidden])", timeout=10_000)
    assert page.inner_text("#code") == CODE
    page.wait_for_url(f"{PLATFORM}/complete?cc={CODE}", timeout=10_000)
    context.close()


def rss_kb(pid):
    with open(f"/proc/{pid}/status") as f:
        return next(int(line.split()[1]) for line in f if line.startswith("VmRSS:"))


def test_scripted_joins_cannot_close_the_study(study, browser):
    state = study["launch"]("--max-sessions", "5")
    record = study["record"]
    # Bots from ten machines join with consent and never act: more than the study's cap
    # (3) and the sessions held at once (5).
    for n in range(10):
        status, _, body = request(study, "POST", "/join", "consent=agree&" + ids(f"bot{n}"), source=f"127.0.0.{n + 2}")
        assert status in (303, 503), (status, body)

    # A real participant still gets in, plays, and is counted; the bots left nothing.
    context = browser.new_context()
    page = context.new_page()
    arrive(page, study, "R1")
    agree_and_begin(page)
    page.wait_for_load_state("load")
    assert "/s/" in page.url, page.inner_text("body")
    wait_view(page)
    page.keyboard.press("1")
    wait_view(page, "view.steps === 1")
    assert len(list(record.glob("p*.jsonl"))) == 1

    # After a restart on the same folder the count is the same: one participant, not eleven.
    state["procs"][-1].terminate()
    state["procs"][-1].wait()
    study["launch"]()
    researcher = study["links"]["researcher"].replace("/results/", "/api/results/").split(f":{study['port']}", 1)[1]
    status, _, body = request(study, "GET", researcher)
    assert json.loads(body)["admitted"] == 1
    page2 = context.new_page()
    arrive(page2, study, "R2")
    begin_session(page2)
    context.close()


def test_joins_from_one_address_are_rate_limited(study):
    study["launch"]()
    statuses = [request(study, "POST", "/join", "consent=agree&" + ids(f"flood{n}"), source="127.0.0.9")[0] for n in range(40)]
    assert 429 in statuses, statuses
    # Another address is not held back by that one.
    assert request(study, "POST", "/join", "consent=agree&" + ids("other"), source="127.0.0.10")[0] == 303


def test_a_thousand_scripted_joins_cost_at_most_100_mb(study):
    """Sessions that never act share their condition's model: 1,000 of them (from 1,000
    addresses, under the per-address bound) raise the server's memory by at most 100 MB.
    `pytest -s` prints the figure docs/serve.md gives."""
    state = study["launch"]("--max-sessions", "1010")
    pid = state["procs"][-1].pid
    before = rss_kb(pid)
    statuses = [
        request(study, "POST", "/join", "consent=agree&" + ids(f"bot{n}"), source=f"127.0.{1 + n // 250}.{2 + n % 250}")[0]
        for n in range(1000)
    ]
    after = rss_kb(pid)
    assert statuses.count(303) == 1000, sorted(set(statuses))
    grown = (after - before) / 1024
    print(f"1,000 joins that never act: RSS {before / 1024:.1f} MB -> {after / 1024:.1f} MB, "
          f"+{grown:.1f} MB, {(after - before) / 1000:.1f} KB a session")
    assert grown <= 100, f"{grown:.1f} MB"
    assert not study["record"].exists() or not any(study["record"].glob("p*.jsonl"))
