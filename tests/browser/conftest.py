"""Fixtures of the browser tests: ``browser`` (one headless Chromium per test process) and ``open_page``.

``open_page(path)`` opens a local HTML file in a new page and returns a
:class:`~tests.browser.harness.RenderedPage`; the page closes after the test.  If the browser cannot
start, every test that uses it fails with the reason (it is never skipped: CI installs Chromium).
Browser tests are slow (mark them ``@pytest.mark.slow``).
"""

from __future__ import annotations

import pytest

from tests.browser.harness import BrowserUnavailable, RenderedPage, close, launch


@pytest.fixture(scope="session")
def browser(tmp_path_factory):
    """A headless Chromium context with a fresh profile, shared by the tests of one process."""
    try:
        playwright, context = launch(tmp_path_factory.mktemp("chromium-profile"))
    except BrowserUnavailable as exc:
        pytest.fail(str(exc), pytrace=False)
    yield context
    close(playwright, context)


@pytest.fixture
def open_page(browser):
    """``open_page(path)``: the local HTML file at ``path`` open in a new page (closed after the test)."""
    pages = []

    def opener(path):
        page = browser.new_page()
        pages.append(page)
        return RenderedPage(page).open(path)

    yield opener
    for page in pages:
        page.close()
