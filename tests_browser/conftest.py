"""Headless Chromium for the browser tests: Debian's /usr/bin/chromium driven by playwright.

Playwright never downloads a browser here: it launches the system's Chromium
(``BEATSYNC_CHROMIUM``, default ``/usr/bin/chromium``; ``.ci/run`` installs Debian's
``chromium`` package when it is missing) with a fresh profile, no background
networking, and every request of every page watched: only ``file:``, ``data:``,
``blob:``, ``about:`` and the loopback address may be asked for; anything else is
blocked and recorded, and fails the test that caused it.
"""

from __future__ import annotations

import functools
import os
import subprocess
import sys
import threading
from dataclasses import dataclass, field
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from urllib.parse import urlsplit

import pytest

ROOT = Path(__file__).resolve().parents[1]
SITE = ROOT / "docs" / "_build" / "html"
FIXTURES = Path(__file__).resolve().parent / "fixtures"
CHROMIUM = Path(os.environ.get("BEATSYNC_CHROMIUM", "/usr/bin/chromium"))
CHROMIUM_ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]
LOCAL_SCHEMES = {"file", "data", "blob", "about"}
LOOPBACK = {"127.0.0.1"}


def is_local(url: str) -> bool:
    """Whether a request stays on this machine: a file, inline data, or the loopback host."""
    parts = urlsplit(url)
    if parts.scheme in LOCAL_SCHEMES:
        return True
    return parts.scheme in {"http", "ws"} and parts.hostname in LOOPBACK


@dataclass
class Watch:
    """What went wrong on one page: console errors, uncaught errors, failed or outside requests."""

    console_errors: list[str] = field(default_factory=list)
    page_errors: list[str] = field(default_factory=list)
    failed_requests: list[str] = field(default_factory=list)
    outside_requests: list[str] = field(default_factory=list)

    def attach(self, page) -> Watch:
        page.on("console", self._console)
        page.on("pageerror", lambda exc: self.page_errors.append(str(exc)))
        page.on("requestfailed", self._failed)
        page.on("request", self._request)
        page.on("response", self._response)
        return self

    def _console(self, message) -> None:
        if message.type == "error":
            self.console_errors.append(f"{message.text} at {message.location.get('url')}")

    def _failed(self, request) -> None:
        self.failed_requests.append(f"{request.url[:120]}: {request.failure}")

    def _request(self, request) -> None:
        if not is_local(request.url):
            self.outside_requests.append(request.url)

    def _response(self, response) -> None:
        if response.status >= 400:
            self.failed_requests.append(f"{response.url[:120]}: HTTP {response.status}")

    def problems(self) -> dict[str, list[str]]:
        names = ("console_errors", "page_errors", "failed_requests", "outside_requests")
        return {name: getattr(self, name) for name in names if getattr(self, name)}


@pytest.fixture(scope="session")
def chromium() -> Path:
    if not CHROMIUM.is_file():
        pytest.fail(
            f"no Chromium at {CHROMIUM}: install Debian's package (apt-get install -y chromium) "
            "or set BEATSYNC_CHROMIUM"
        )
    return CHROMIUM


@pytest.fixture(scope="session")
def browser(chromium, tmp_path_factory):
    """One headless Chromium with a fresh profile; requests leaving the machine are blocked."""
    from playwright.sync_api import sync_playwright

    blocked: list[str] = []

    def guard(route):
        if is_local(route.request.url):
            route.continue_()
        else:
            blocked.append(route.request.url)
            route.abort("blockedbyclient")

    with sync_playwright() as playwright:
        context = playwright.chromium.launch_persistent_context(
            str(tmp_path_factory.mktemp("chromium-profile")),
            executable_path=str(chromium),
            headless=True,
            args=CHROMIUM_ARGS,
            viewport={"width": 1280, "height": 800},
        )
        context.route("**/*", guard)
        context.blocked = blocked
        yield context
        context.close()
    assert not blocked, f"requests left the machine: {blocked}"


@pytest.fixture(scope="session")
def site() -> Path:
    if not (SITE / "index.html").is_file():
        pytest.fail(f"no site at {SITE}: run `make docs` first (`make test-browser` does)")
    return SITE


class _QuietHandler(SimpleHTTPRequestHandler):
    def log_message(self, format, *args) -> None:  # noqa: A002 (the base class's name)
        pass


@pytest.fixture(scope="session")
def served_site(site):
    """The built site served over HTTP on a free loopback port: its base URL."""
    handler = functools.partial(_QuietHandler, directory=str(site))
    server = ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{server.server_address[1]}/"
    server.shutdown()
    server.server_close()
    thread.join()


@pytest.fixture(scope="session")
def fixture_site(tmp_path_factory) -> Path:
    """tests_browser/fixtures/site built with the site's own settings (docs/conf.py)."""
    out = tmp_path_factory.mktemp("fixture-site")
    build = subprocess.run(
        [
            sys.executable,
            "-m",
            "sphinx",
            "-b",
            "html",
            "-W",
            "-q",
            "-d",
            str(out / "doctrees"),
            str(FIXTURES / "site"),
            str(out / "html"),
        ],
        capture_output=True,
        text=True,
    )
    assert build.returncode == 0, build.stdout + build.stderr
    return out / "html"
