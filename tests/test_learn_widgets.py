"""beatsync.learn.widgets: a live slider whose states are also precomputed for a static page."""

import re
import shutil
import subprocess

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from IPython.display import Audio  # noqa: E402

from beatsync import ParameterError  # noqa: E402
from beatsync.learn.widgets import explore  # noqa: E402


@pytest.fixture
def calls():
    return []


@pytest.fixture
def view(calls):
    def update(slope, shift):
        calls.append((slope, shift))
        fig, ax = plt.subplots(figsize=(2, 1))
        ax.plot(np.arange(5) * slope + shift)
        return fig

    return explore(update, slope=[1.0, 2.0], shift=[0, 3, 5])


def _states(page):
    return re.findall(r'<div data-state="([0-9-]+)"( style="display:none")?>', page)


def test_static_page_holds_every_combination_first_shown(view):
    page = view._repr_mimebundle_()["text/html"]
    states = _states(page)
    assert [k for k, _ in states] == ["0-0", "0-1", "0-2", "1-0", "1-1", "1-2"]
    assert [hidden == "" for _, hidden in states] == [True] + [False] * 5
    assert "precomputed for: slope = 1, 2; shift = 0, 3, 5" in page
    assert page.count('type="range"') == 2
    assert len(set(re.findall(r"data:image/png;base64,([^\"]+)", page))) == 6  # 6 distinct figures
    assert "http" not in page  # no request leaves the page


def test_each_combination_is_computed_once(view, calls):
    view.to_html()
    view._repr_mimebundle_()
    view.render(slope=2.0, shift=5)
    assert sorted(calls) == sorted((a, b) for a in (1.0, 2.0) for b in (0, 3, 5))
    view.clear()
    view.render(slope=2.0, shift=5)
    assert calls[-1] == (2.0, 5) and len(calls) == 7


def test_live_slider_reruns_update_with_the_new_value(view, calls):
    box = view.widget()
    slope, shift, _ = box.children
    assert calls == [(1.0, 0)]
    shift.value = 3
    slope.value = 2.0
    assert calls == [(1.0, 0), (1.0, 3), (2.0, 3)]
    assert "application/vnd.jupyter.widget-view+json" in view._repr_mimebundle_()


def test_extras_are_shown_under_each_state():
    def update(rate):
        return plt.figure(figsize=(1, 1)), Audio(np.sin(np.arange(800)), rate=rate)

    page = explore(update, rate=[8000, 16000]).to_html()
    assert page.count("<audio") == 2 and page.count("data:audio/wav;base64,") == 2


@pytest.mark.parametrize(
    ("sliders", "match"),
    [
        ({}, "no slider"),
        ({"alpha": 0.3}, "alpha=0.3"),
        ({"alpha": []}, r"alpha=\[\]"),
        ({"band": [[0, 200]]}, r"band=\[\[0, 200\]\]"),
        ({"a": range(5), "b": range(5)}, "max_states=24"),
    ],
)
def test_bad_sliders_raise(sliders, match):
    with pytest.raises(ParameterError, match=match):
        explore(lambda **kw: plt.figure(), **sliders)


def test_update_must_return_a_figure():
    with pytest.raises(ParameterError, match="int"):
        explore(lambda a: 3, a=[1]).render(a=1)


PROBE = """<script>
var r = document.querySelector('.beatsync-explore');
var ins = r.querySelectorAll('input[type=range]');
ins[0].value = 1; ins[0].dispatchEvent(new Event('input'));
ins[1].value = 2; ins[1].dispatchEvent(new Event('input'));
var shown = [].filter.call(r.querySelectorAll('div[data-state]'),
    function (d) { return d.style.display !== 'none'; });
document.title = 'SHOWN=' + shown.map(function (d) { return d.dataset.state; }).join(',')
    + ' LABELS=' + [].map.call(ins, function (i) { return i.nextElementSibling.textContent; });
</script>"""


@pytest.mark.slow
@pytest.mark.skipif(shutil.which("chromium") is None, reason="needs Debian's chromium")
def test_static_slider_swaps_the_figure_in_a_browser(view, tmp_path):
    page = tmp_path / "page.html"
    page.write_text(
        f"<html><head><title>-</title></head><body>{view.to_html()}{PROBE}</body></html>"
    )
    dom = subprocess.run(
        ["chromium", "--headless", "--no-sandbox", "--disable-gpu", "--dump-dom", page.as_uri()],
        capture_output=True, text=True, timeout=120, check=True,
    ).stdout  # fmt: skip
    assert "<title>SHOWN=1-2 LABELS=2,5</title>" in dom
