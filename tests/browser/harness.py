"""Headless Chromium for the browser tests: open a local HTML file, read its rendered DOM, take screenshots.

The browser is Debian's Chromium at :data:`CHROMIUM` (``.ci/run`` installs it when it is missing), driven
by the ``playwright`` package (pinned in the ``test`` extra; its own browser download is never used).
Playwright rather than the bare command line (``chromium --headless --dump-dom``): a test measures the
laid-out page (``getBoundingClientRect``, computed styles, scroll widths) and follows links, which a DOM
dump cannot tell.

:func:`launch` starts one browser; :class:`RenderedPage` wraps one open page with the few questions the
tests ask of it.  The fixtures of ``conftest.py`` beside this file give both to a test.
"""

from __future__ import annotations

import json
from pathlib import Path

CHROMIUM = Path("/usr/bin/chromium")

#: What Chromium needs on this machine (root, no GPU, no display) and to stay offline and quiet: no
#: sandbox (it refuses to run as root with one), no GPU process, no background fetches, updates or sync.
CHROMIUM_ARGS = ("--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update",
                 "--disable-sync", "--no-first-run")

#: The window the pages are laid out in, in CSS pixels: a desktop page, as an engineer reads a report.
VIEWPORT = {"width": 1400, "height": 900}


class BrowserUnavailable(RuntimeError):
    """Chromium (or playwright) could not start: the browser tests fail with this message, never skip."""


def launch(user_data_dir: Path):
    """Start headless Chromium with a fresh profile in ``user_data_dir``; returns ``(playwright, context)``.

    Stop both with :func:`close`.  No timeouts are set on the browser's actions: a slow, shared machine
    must not fail a test; a page that never loads is a hang that the CI run's own limit ends.

    Raises
    ------
    BrowserUnavailable
        playwright is not installed, :data:`CHROMIUM` is missing, or the browser does not start.
    """
    try:
        from playwright.sync_api import sync_playwright
    except ImportError as exc:
        raise BrowserUnavailable(f"the browser tests need playwright (pip install '.[test]'): {exc}") from None
    if not CHROMIUM.exists():
        raise BrowserUnavailable(f"{CHROMIUM} is missing: install it (apt-get install chromium; .ci/run does)")
    playwright = sync_playwright().start()
    try:
        context = playwright.chromium.launch_persistent_context(
            str(user_data_dir), executable_path=str(CHROMIUM), headless=True, args=list(CHROMIUM_ARGS),
            viewport=VIEWPORT, timeout=0)
    except Exception as exc:
        playwright.stop()
        raise BrowserUnavailable(f"headless Chromium at {CHROMIUM} did not start: {exc}") from None
    context.set_default_timeout(0)
    context.set_default_navigation_timeout(0)
    return playwright, context


def close(playwright, context) -> None:
    """Stop the browser and the playwright driver that :func:`launch` started."""
    try:
        context.close()
    finally:
        playwright.stop()


# The page-side half of RenderedPage.overflowing: elements whose right edge passes the viewport, except those
# inside a box that scrolls or clips sideways (an equation box; what overflows there stays in it).
_OVERFLOWING = """() => {
  const width = document.documentElement.clientWidth;
  const clipped = (el) => {
    for (let p = el.parentElement; p; p = p.parentElement) {
      if (['auto', 'scroll', 'hidden', 'clip'].includes(getComputedStyle(p).overflowX)) return true;
    }
    return false;
  };
  const out = [];
  for (const el of document.body.querySelectorAll('*')) {
    const r = el.getBoundingClientRect();
    if (r.width > 0 && (r.right > width + 0.5 || r.left < -0.5) && !clipped(el)) {
      const name = el.tagName.toLowerCase() + (el.id ? '#' + el.id : '');
      out.push(name + ' ' + Math.round(r.left) + '..' + Math.round(r.right));
    }
  }
  return out;
}"""


class RenderedPage:
    """One page open in the browser, and what a test asks of its rendered DOM.

    ``page`` is the playwright page, for anything else (clicks, navigation, keyboard).
    """

    def __init__(self, page):
        self.page = page

    def open(self, path: Path) -> "RenderedPage":
        """Load a local file and wait until it is laid out (fonts included)."""
        self.page.goto(Path(path).resolve().as_uri(), wait_until="load")
        self.page.evaluate("document.fonts.ready.then(() => true)")
        return self

    def evaluate(self, script: str, argument=None):
        """The value of a JavaScript expression or function on the page (JSON-like values)."""
        return self.page.evaluate(script, argument)

    def count(self, selector: str) -> int:
        return self.page.locator(selector).count()

    def texts(self, selector: str) -> list[str]:
        """The ``textContent`` of every element matching ``selector``, in document order."""
        return self.evaluate("(s) => Array.from(document.querySelectorAll(s), e => e.textContent)", selector)

    def text(self) -> str:
        """The page's visible text (``innerText`` of the body)."""
        return self.evaluate("document.body.innerText")

    def rects(self, selector: str) -> list[dict]:
        """``getBoundingClientRect`` (left, top, right, bottom, width, height; CSS pixels) of each match."""
        return self.evaluate("(s) => Array.from(document.querySelectorAll(s), e => e.getBoundingClientRect()"
                             ".toJSON())", selector)

    def style(self, selector: str, prop: str) -> list[str]:
        """The computed value of CSS property ``prop`` for each element matching ``selector``."""
        return self.evaluate("([s, p]) => Array.from(document.querySelectorAll(s), e => getComputedStyle(e)"
                             ".getPropertyValue(p))", [selector, prop])

    def page_width(self) -> dict:
        """The document's scroll width and the viewport's width: the page overflows sideways if the first is larger."""
        return self.evaluate("({scroll: document.documentElement.scrollWidth,"
                             " viewport: document.documentElement.clientWidth})")

    def overflowing(self) -> list[str]:
        """The elements that pass the viewport's sides outside any sideways-scrolling box (none, on a good page)."""
        return self.evaluate(_OVERFLOWING)

    def screenshot(self, path: Path, *, full_page: bool = True) -> Path:
        """A PNG of the page (all of it by default) at ``path``."""
        self.page.screenshot(path=str(path), full_page=full_page)
        return Path(path)

    def __repr__(self) -> str:
        return f"RenderedPage({json.dumps(self.page.url)})"
