"""JupyterLab in headless Chromium: a notebook runs and an ipywidgets slider updates its output.

The server is started here on a free loopback port, token-less, with a temporary root
folder holding a copy of the tests' widget notebook, and fresh settings, workspaces and
runtime folders, so nothing of the user's own JupyterLab is read or written.
"""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
import sys
import time
import urllib.request

import pytest

from conftest import FIXTURES, Watch

NOTEBOOK = FIXTURES / "site" / "widgets.ipynb"


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def lab(tmp_path_factory):
    """A JupyterLab server on 127.0.0.1 serving a temporary root with the widget notebook."""
    home = tmp_path_factory.mktemp("lab")
    root = home / "root"
    root.mkdir()
    shutil.copy(NOTEBOOK, root / "widgets.ipynb")
    port = _free_port()
    env = dict(
        os.environ,
        JUPYTER_CONFIG_DIR=str(home / "config"),
        JUPYTER_RUNTIME_DIR=str(home / "runtime"),
        IPYTHONDIR=str(home / "ipython"),
    )
    server = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "jupyterlab",
            "--no-browser",
            "--ip=127.0.0.1",
            f"--port={port}",
            "--IdentityProvider.token=",
            "--ServerApp.password=",
            "--ServerApp.port_retries=0",
            "--allow-root",
            f"--ServerApp.root_dir={root}",
            f"--LabApp.user_settings_dir={home / 'settings'}",
            f"--LabApp.workspaces_dir={home / 'workspaces'}",
        ],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=open(home / "server.log", "w"),
    )
    url = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + 90
        while True:
            try:
                with urllib.request.urlopen(f"{url}/api/status", timeout=2) as answer:
                    if answer.status == 200:
                        break
            except OSError:
                pass
            if server.poll() is not None or time.monotonic() > deadline:
                pytest.fail("JupyterLab did not start:\n" + (home / "server.log").read_text())
            time.sleep(0.5)
        yield url
    finally:
        server.terminate()
        try:
            server.wait(timeout=20)
        except subprocess.TimeoutExpired:
            server.kill()
            server.wait()


def test_a_notebook_runs_and_its_slider_updates_its_output(browser, lab):
    page = browser.new_page()
    watch = Watch().attach(page)
    try:
        page.goto(f"{lab}/lab/tree/widgets.ipynb", wait_until="load")
        page.wait_for_selector(".jp-Notebook .jp-Cell", timeout=60_000)
        # run only once the kernel is up (the status bar reads "... | Idle")
        page.locator(".jp-StatusBar-TextItem", has_text="| Idle").wait_for(timeout=90_000)
        page.locator(".jp-Notebook").first.click()
        page.get_by_role("menuitem", name="Run", exact=True).click()
        page.get_by_role("menuitem", name="Run All Cells", exact=True).click()
        output_has = (
            "text => [...document.querySelectorAll('.jp-OutputArea-output')]"
            ".some(o => o.textContent.includes(text))"
        )
        page.wait_for_function(output_has, arg="n squared = 9", timeout=90_000)
        handle = page.locator(".jp-OutputArea .widget-slider .noUi-handle").last
        handle.focus()
        handle.press("ArrowRight")
        page.wait_for_function(output_has, arg="n squared = 16", timeout=30_000)
        assert watch.outside_requests == [], watch.outside_requests
        assert watch.page_errors == [], watch.page_errors
        assert watch.console_errors == [], watch.console_errors
    finally:
        page.close()
