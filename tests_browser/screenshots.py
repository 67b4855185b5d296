"""Screenshots of the built site by the same headless Chromium as the browser tests.

    .venv/bin/python tests_browser/screenshots.py     # after `make docs`

Writes ``docs/img/site_home.png`` (the home page) and ``docs/img/site_tutorial.png``,
the first tutorial with a precomputed slider, scrolled to the slider; while there is no
such tutorial, ``docs/img/site_notebook.png``, the segmentation notebook at its figure.
"""

from __future__ import annotations

import re
import sys
import tempfile
from pathlib import Path

from playwright.sync_api import sync_playwright

sys.path.insert(0, str(Path(__file__).resolve().parent))
from conftest import CHROMIUM, CHROMIUM_ARGS, ROOT, SITE, is_local  # noqa: E402

OUT = ROOT / "docs" / "img"


def _second_page() -> tuple[Path, str, str]:
    """The page of the second screenshot, what to scroll to, and the file's name."""
    for page in sorted((SITE / "notebooks" / "tutorials").glob("*.html")):
        if re.search(r"<input[^>]*type=[\"']?range", page.read_text(errors="replace")):
            return page, "input[type=range]", "site_tutorial.png"
    notebook = SITE / "notebooks" / "paper_a_fig02_segmentation.html"
    return notebook, "div.cell_output img", "site_notebook.png"


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    with sync_playwright() as playwright, tempfile.TemporaryDirectory() as profile:
        browser = playwright.chromium.launch_persistent_context(
            profile,
            executable_path=str(CHROMIUM),
            headless=True,
            args=CHROMIUM_ARGS,
            viewport={"width": 1280, "height": 800},
        )
        browser.route("**/*", lambda r: r.continue_() if is_local(r.request.url) else r.abort())
        page = browser.new_page()
        page.goto((SITE / "index.html").as_uri())
        page.wait_for_load_state("networkidle")
        page.screenshot(path=OUT / "site_home.png")
        path, selector, name = _second_page()
        page.goto(path.as_uri())
        page.wait_for_load_state("networkidle")
        target = page.locator(selector).first
        target.scroll_into_view_if_needed()
        page.evaluate("window.scrollBy(0, -120)")
        page.screenshot(path=OUT / name)
        browser.close()
    print(f"wrote {OUT / 'site_home.png'} and {OUT / name} ({path.name})")


if __name__ == "__main__":
    main()
