"""The static site in headless Chromium: every page offline, its media, its sliders.

The site's pages are those `make docs` wrote (docs/_build/html), found when the tests
are collected, so new pages (tutorials, findings) are tested as they are added. The
fixture site (tests_browser/fixtures/site, built with the site's settings) always has
an equation, an audio element and a precomputed slider, whatever the site holds yet.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from conftest import ROOT, SITE, Watch

#: every HTML page of the site (not the assets' own files)
PAGES = sorted(
    p.relative_to(SITE).as_posix()
    for p in SITE.rglob("*.html")
    if not any(part.startswith("_") for part in p.relative_to(SITE).parts)
)


def _pages_with(pattern: str) -> list[str]:
    return [p for p in PAGES if re.search(pattern, (SITE / p).read_text(errors="replace"))]


MEDIA_PAGES = _pages_with(r"<(audio|video)\b")
SLIDER_PAGES = _pages_with(r"<input[^>]*type=[\"']?range")
FIXTURE_PAGES = ["index.html", "widgets.html"]


def _open(browser, path: Path | str):
    """Load a page (a file or a URL), wait until the network is idle and MathJax has
    typeset the page's math."""
    page = browser.new_page()
    watch = Watch().attach(page)
    page.goto(path if isinstance(path, str) else path.as_uri(), wait_until="load")
    page.wait_for_load_state("networkidle")
    if page.locator("div.math, span.math").count():
        page.wait_for_selector("mjx-container", state="attached", timeout=20_000)
    return page, watch


def _check_page(browser, path: Path | str) -> None:
    page, watch = _open(browser, path)
    try:
        assert page.title() and len(page.inner_text("body")) > 100, f"{path}: empty page"
        assert watch.problems() == {}, f"{path}: {watch.problems()}"
    finally:
        page.close()


def test_the_site_has_its_pages():
    assert "index.html" in PAGES, "run `make docs` first (`make test-browser` does)"
    for page in ("install.html", "cli.html", "api.html"):
        assert page in PAGES
    assert any(p.startswith("notebooks/paper_") for p in PAGES)


def test_every_notebook_has_its_page():
    notebooks = sorted(ROOT.glob("notebooks/*.ipynb")) + sorted(
        ROOT.glob("notebooks/tutorials/*.ipynb")
    )
    assert notebooks
    for notebook in notebooks:
        page = notebook.relative_to(ROOT).with_suffix(".html").as_posix()
        assert page in PAGES, page


def test_references_cover_every_subcommand_and_public_name():
    import importlib

    from beatsync.commands import COMMAND_MODULES

    cli = (SITE / "cli.html").read_text()
    for command in COMMAND_MODULES:
        assert f'id="beatsync-{command}"' in cli, command
    api = (SITE / "api.html").read_text()
    for module in ("segment", "beats", "sync", "graph", "evaluate", "io", "learn"):
        package = importlib.import_module(f"beatsync.{module}")
        for name in package.__all__:
            if callable(getattr(package, name)):  # functions and classes (constants: their
                # doc comment is in the submodule that defines them)
                assert f'id="beatsync.{module}.{name}"' in api, f"beatsync.{module}.{name}"


@pytest.mark.parametrize("page", PAGES)
def test_page_loads_offline_without_errors(browser, site, page):
    _check_page(browser, site / page)


@pytest.mark.parametrize("page", PAGES)
def test_served_page_loads_offline_without_errors(browser, served_site, page):
    _check_page(browser, served_site + page)


@pytest.mark.parametrize("page", FIXTURE_PAGES)
def test_fixture_page_loads_offline_without_errors(browser, fixture_site, page):
    _check_page(browser, fixture_site / page)


def test_math_is_typeset_by_the_local_mathjax(browser, fixture_site):
    page, watch = _open(browser, fixture_site / "widgets.html")
    try:
        assert page.locator("mjx-container").count() >= 1
        scripts = page.eval_on_selector_all("script[src]", "els => els.map(e => e.src)")
        mathjax = [s for s in scripts if "mathjax" in s.lower()]
        assert mathjax and all(s.startswith("file://") for s in mathjax), mathjax
    finally:
        page.close()


def _media_durations(browser, path: Path) -> list[dict]:
    page, watch = _open(browser, path)
    try:
        page.evaluate(
            """() => document.querySelectorAll('audio, video').forEach(m => {
                   if (m.preload === 'none') { m.preload = 'metadata'; m.load(); } })"""
        )
        page.wait_for_function(
            """() => [...document.querySelectorAll('audio, video')]
                     .every(m => m.readyState >= 1 || m.error)""",
            timeout=20_000,
        )
        media = page.eval_on_selector_all(
            "audio, video",
            "els => els.map(m => ({tag: m.tagName, duration: m.duration,"
            " error: m.error && m.error.code}))",
        )
        assert watch.problems() == {}, watch.problems()
        return media
    finally:
        page.close()


@pytest.mark.parametrize("page", MEDIA_PAGES)
def test_every_audio_and_video_element_loads(browser, site, page):
    media = _media_durations(browser, site / page)
    assert media
    for element in media:
        assert element["error"] is None and element["duration"] > 0, (page, element)


def test_fixture_audio_element_loads(browser, fixture_site):
    media = _media_durations(browser, fixture_site / "widgets.html")
    assert [m["tag"] for m in media] == ["AUDIO"]
    assert media[0]["duration"] == pytest.approx(1.0, abs=0.01)


def _sliders_change_their_figures(browser, path: Path) -> int:
    """Move every precomputed slider of a page; each must change an image beside it."""
    page, watch = _open(browser, path)
    try:
        sliders = page.locator("input[type=range]")
        count = sliders.count()
        for i in range(count):
            slider = sliders.nth(i)
            # the images shown in the output the slider is in (its cell output, else the
            # slider's grandparent): a new src, or another image shown, is a new figure
            srcs = """s => [...(s.closest('.cell_output, .output') || s.parentElement.parentElement)
                            .querySelectorAll('img')]
                       .filter(i => i.offsetParent !== null
                                    && getComputedStyle(i).visibility !== 'hidden')
                       .map(i => i.src)"""
            before = slider.evaluate(srcs)
            assert before, f"{path.name}: slider {i} has no figure beside it"
            at_max = slider.evaluate("s => s.value === s.max")
            slider.press("Home" if at_max else "End")
            after = slider.evaluate(srcs)
            assert after, f"{path.name}: slider {i} moved to a state with no figure"
            assert after != before, f"{path.name}: slider {i} did not change its figure"
        assert watch.problems() == {}, watch.problems()
        return count
    finally:
        page.close()


@pytest.mark.parametrize("page", SLIDER_PAGES)
def test_precomputed_sliders_change_their_figure(browser, site, page):
    assert _sliders_change_their_figures(browser, site / page) >= 1


def test_fixture_precomputed_slider_changes_its_figure(browser, fixture_site):
    # the output carries an ipywidgets view and text/html: the site shows the text/html
    html = (fixture_site / "widgets.html").read_text()
    assert "precomputed for: frequency = 1, 2, 3" in html
    assert _sliders_change_their_figures(browser, fixture_site / "widgets.html") == 1
