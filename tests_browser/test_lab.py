"""JupyterLab in headless Chromium: a real tutorial runs and its live slider redraws its figure.

The server is started here on a free loopback port, token-less, with a temporary root
folder holding a copy of the tutorial with its outputs cleared (so every output the
test sees was made by this run), and fresh settings, workspaces and runtime folders,
so nothing of the user's own JupyterLab is read or written. The kernel is the
project's Python, which finds the repository's ``data/`` through the installed
package (``BEATSYNC_DATA`` names it too, for an installation that is not editable).
"""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import time
import urllib.request

import nbformat
import pytest
from playwright.sync_api import TimeoutError as PlaywrightTimeout

from conftest import ROOT, Watch

#: the tutorial that runs fastest top to bottom (real dancers, one live view `view`)
TUTORIAL = ROOT / "notebooks" / "tutorials" / "05_real_dancers.ipynb"
#: printed by the tutorial's last cell
LAST_OUTPUT = "notebook ran in"


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _copy_cleared(source, target) -> None:
    nb = nbformat.read(source, as_version=4)
    for cell in nb.cells:
        if cell.cell_type == "code":
            cell.outputs = []
            cell.execution_count = None
    nbformat.write(nb, target)


@pytest.fixture(scope="module")
def lab(tmp_path_factory):
    """A JupyterLab server on 127.0.0.1 serving a temporary root with the tutorial."""
    home = tmp_path_factory.mktemp("lab")
    root = home / "root"
    root.mkdir()
    _copy_cleared(TUTORIAL, root / TUTORIAL.name)
    port = _free_port()
    env = dict(
        os.environ,
        BEATSYNC_DATA=str(ROOT / "data"),
        JUPYTER_CONFIG_DIR=str(home / "config"),
        JUPYTER_DATA_DIR=str(home / "data"),
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
            # the server itself asks nothing of the internet either
            "--LabApp.news_url=None",
            "--LabApp.check_for_updates_class=jupyterlab.NeverCheckForUpdate",
            "--LabApp.extension_manager=readonly",
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


#: a code cell's execution count ("[ ]:" not run, "[*]:" running or queued, "[3]:" ran)
PROMPT = ".jp-CodeCell .jp-InputArea-prompt"
#: what a cell wrote to stderr, tracebacks included
STDERR = ".jp-OutputArea-output[data-mime-type='application/vnd.jupyter.stderr']"
#: the live view of `view = explore(...)`: its sliders above the figure it draws
VIEW = ".jp-OutputArea-output .widget-vbox:has(.widget-slider)"


def test_a_tutorial_runs_and_its_slider_redraws_its_figure(browser, lab):
    page = browser.new_page()
    watch = Watch().attach(page)
    try:
        page.goto(f"{lab}/lab/tree/{TUTORIAL.name}", wait_until="load")
        page.wait_for_selector(".jp-Notebook .jp-Cell", timeout=60_000)
        # run only once the kernel is up (the status bar reads "... | Idle")
        page.locator(".jp-StatusBar-TextItem", has_text="| Idle").wait_for(timeout=90_000)
        page.locator(".jp-Notebook").first.click()
        page.get_by_role("menuitem", name="Run", exact=True).click()
        page.get_by_role("menuitem", name="Run All Cells", exact=True).click()
        # Run All queues every cell ("[*]:"); it is over when none is queued any more:
        # each shows its execution count, or the run stopped at an error and the cells
        # after it show "[ ]:" again
        page.wait_for_function(
            """prompt => {
                   const texts = [...document.querySelectorAll(prompt)]
                       .map(p => p.textContent.trim());
                   return !texts.includes('[*]:') && texts.some(t => /^\\[\\d+\\]:$/.test(t)); }""",
            arg=PROMPT,
            timeout=150_000,
        )
        prompts = page.eval_on_selector_all(PROMPT, "els => els.map(e => e.textContent.trim())")
        stderr = page.eval_on_selector_all(STDERR, "els => els.map(e => e.textContent)")
        # every code cell ran once, in order
        assert prompts == [f"[{n}]:" for n in range(1, len(prompts) + 1)], (prompts, stderr)
        page.wait_for_function(
            """text => [...document.querySelectorAll('.jp-OutputArea-output')]
                      .some(o => o.textContent.includes(text))""",
            arg=LAST_OUTPUT,
            timeout=10_000,
        )

        view = page.locator(VIEW)
        assert view.count() == 1, "the tutorial's live view (an ipywidgets VBox) is not shown"
        view.scroll_into_view_if_needed()
        figure = view.locator("img")
        figure.wait_for(timeout=30_000)
        before = figure.get_attribute("src")
        assert before.startswith("data:image/png;base64,")
        slider = view.locator(".widget-slider").first
        readout = slider.locator(".widget-readout")
        assert readout.inner_text() == "0.05"  # smooth, the first value of its list
        handle = slider.locator(".noUi-handle")
        handle.focus()
        handle.press("ArrowRight")
        try:
            page.wait_for_function(
                """([selector, before]) => {
                       const img = document.querySelector(selector + ' img');
                       return img && img.src.startsWith('data:image/png')
                              && img.src !== before; }""",
                arg=[VIEW, before],
                timeout=30_000,
            )
        except PlaywrightTimeout:
            pytest.fail(f"smooth moved to {readout.inner_text()}: the figure was not redrawn")
        assert readout.inner_text() == "0.1"
        assert watch.outside_requests == [], watch.outside_requests
        assert watch.page_errors == [], watch.page_errors
        assert watch.console_errors == [], watch.console_errors
        assert watch.failed_requests == [], watch.failed_requests
    finally:
        page.close()
