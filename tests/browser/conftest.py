"""The browser tests' page: one headless Chromium (Debian's) per test module."""

import pytest

from browser import CHROMIUM, CHROMIUM_ARGS


@pytest.fixture(scope="module")
def page():
    """A fresh page in headless Chromium, shared by one module's tests."""
    playwright = pytest.importorskip("playwright.sync_api", reason="Playwright is not installed (pip install playwright)")
    if not CHROMIUM.exists():
        pytest.skip(f"{CHROMIUM} is absent (apt-get install chromium)")
    with playwright.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_ARGS)
        page = browser.new_page(viewport={"width": 900, "height": 720})
        yield page
        browser.close()
