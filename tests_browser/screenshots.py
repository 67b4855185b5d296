"""Screenshots of the built site by the same headless Chromium as the browser tests.

    .venv/bin/python tests_browser/screenshots.py     # after `make docs`

Writes into ``docs/img/``: ``site_home.png`` (the home page), ``site_notebook.png``
(the segmentation notebook at its figure) and ``site_tutorial.png`` (the first
tutorial with a precomputed slider, scrolled to the slider, moved once so that the
picture shows the figure it swapped in).
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


def _tutorial() -> Path:
    """The first tutorial page with a precomputed slider."""
    for page in sorted((SITE / "notebooks" / "tutorials").glob("*.html")):
        if re.search(r"<input[^>]*type=[\"']?range", page.read_text(errors="replace")):
            return page
    raise SystemExit(f"no tutorial page with a slider in {SITE}: run `make docs` first")


def _shoot(page, path: Path, selector: str, name: str, *, move: bool = False) -> None:
    page.goto(path.as_uri())
    page.wait_for_load_state("networkidle")
    target = page.locator(selector).first
    if move:  # a slider: one step, so that its figure is one it swapped in
        target.press("ArrowRight")
        target.blur()
    # one scroll down from the top (furo shows its "back to top" button on a scroll up)
    target.evaluate("e => window.scrollTo(0, e.getBoundingClientRect().top + window.scrollY - 80)")
    page.screenshot(path=OUT / name)


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
        notebook = SITE / "notebooks" / "paper_a_fig02_segmentation.html"
        _shoot(page, notebook, "div.cell_output img", "site_notebook.png")
        tutorial = _tutorial()
        _shoot(page, tutorial, "input[type=range]", "site_tutorial.png", move=True)
        browser.close()
    print(f"wrote site_home.png, site_notebook.png, site_tutorial.png ({tutorial.name}) in {OUT}")


if __name__ == "__main__":
    main()
