"""What the browser tests share: the binary under test, Debian's Chromium driven by
Playwright, and waiting on the page's state (`view`) safely."""

import os
import pathlib
import subprocess
import time

ROOT = pathlib.Path(__file__).resolve().parents[2]
BINARY = pathlib.Path(os.environ.get("BLOCKSTACK_BIN", ROOT / "target" / "release" / "blockstack"))
CHROMIUM = pathlib.Path(os.environ.get("CHROMIUM", "/usr/bin/chromium"))
CHROMIUM_ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]
SHOTS = pathlib.Path(os.environ.get("BLOCKSTACK_SCREENSHOTS", ROOT / "target" / "browser-shots"))
NAMES = ["up", "down", "left", "right", "drop"]

# The page's state, `view`, is a script variable: until the page's script has run (just
# after a navigation, such as #begin's to /s/<token>) the name is not defined, and a bare
# `view` in a wait would throw instead of waiting. Every wait on it starts with this.
READY = "typeof view !== 'undefined' && view !== null"


def run(*args):
    """The binary's standard output for `args`."""
    return subprocess.run([str(BINARY), *map(str, args)], check=True, capture_output=True, text=True).stdout


def action_name(index):
    """An action's name as `blockstack solve` prints it."""
    return NAMES[index] if index < 5 else f"pick {index - 5}"


def view(page):
    """The page's current view (the server's last answer)."""
    return page.evaluate("view")


def wait_until(page, condition, timeout=10_000):
    """Waits until the JavaScript expression `condition` holds on the page. Polled with
    `page.evaluate`, not `page.wait_for_function`: a string predicate of the latter runs
    through `eval`, which the page's Content-Security-Policy refuses (as it should)."""
    deadline = time.monotonic() + timeout / 1000
    while True:
        try:
            if page.evaluate(condition):
                return
        except Exception as e:  # a navigation under way destroys the context: ask again
            if "context" not in str(e).lower() and "navigat" not in str(e).lower():
                raise
        if time.monotonic() > deadline:
            raise AssertionError(f"waited {timeout} ms for {condition} on {page.url}")
        time.sleep(0.05)


def wait_view(page, condition="true", timeout=10_000):
    """Waits until the page's script has made its view and `condition` (JavaScript) holds."""
    wait_until(page, f"{READY} && ({condition})", timeout)


def start_server(*args):
    """`blockstack serve --port 0 ARGS...`: the process and its links by name
    (`participants`, `researcher`)."""
    if not BINARY.exists():
        raise AssertionError(f"{BINARY} is missing: build it with `cargo build --release`")
    proc = subprocess.Popen([str(BINARY), "serve", "--port", "0", *map(str, args)], stdout=subprocess.PIPE, text=True)
    links = {}
    while len(links) < 2:
        line = proc.stdout.readline()
        assert line, "the server ended before serving"
        key, _, url = line.partition(":")
        links[key.strip()] = url.strip()
    return proc, links
