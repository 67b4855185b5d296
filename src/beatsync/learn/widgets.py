"""Live sliders for the tutorials that keep working on a static page.

``explore(update, alpha=[0.1, 0.3, 1.0], ...)`` returns an :class:`Explorer`. In a
kernel it is an ipywidgets view: a ``SelectionSlider`` per parameter, ``update(**values)``
re-run as one moves. The same display carries ``text/html``: every combination rendered
when the cell runs, as PNG images (and any audio) swapped by ``<input type=range>`` and
a few lines of inline JavaScript, so a page built from the executed notebook keeps a
working slider with no kernel and no request leaving the page.

``update`` returns a matplotlib Figure, or ``(figure, extra)`` where ``extra`` (or each
of a list) has ``_repr_html_`` (``IPython.display.Audio``, ``HTML``), shown below it.
Both views share one cache of rendered states, so each combination is computed once.
Whatever does not depend on the sliders belongs outside ``update``.
"""

from __future__ import annotations

import base64
import hashlib
import html
import io
import itertools
import json
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from beatsync.errors import ParameterError

__all__ = ["Explorer", "State", "explore"]

#: at most this many combinations are precomputed for the static page by default
MAX_STATES = 24


@dataclass(frozen=True)
class State:
    """One rendered combination: the figure as PNG bytes and the extras as HTML."""

    png: bytes
    extra_html: str = ""

    def html(self) -> str:
        img = base64.b64encode(self.png).decode("ascii")
        return f'<img style="max-width:100%" src="data:image/png;base64,{img}"/>{self.extra_html}'


def explore(
    update: Callable[..., Any], *, max_states: int = MAX_STATES, **sliders: Sequence[Any]
) -> Explorer:
    """A slider per keyword (name -> its hashable values) over ``update(**values)``; the
    first value of each list is shown first. At most ``max_states`` combinations: each
    is a PNG in the executed notebook."""
    if not callable(update):
        raise ParameterError(f"update={update!r} is not callable: pass the function itself")
    if not sliders:
        raise ParameterError("no slider given: pass each as name=[values], e.g. alpha=[0.1, 0.3]")
    values = {}
    for name, vals in sliders.items():
        if isinstance(vals, (str, bytes)) or not hasattr(vals, "__iter__"):
            raise ParameterError(f"slider {name}={vals!r} is one value: give a list of values")
        vals = list(vals)
        if not vals:
            raise ParameterError(f"slider {name}=[] has no values: give a list of them")
        try:
            [hash(v) for v in vals]
        except TypeError:
            raise ParameterError(
                f"slider {name}={sliders[name]!r} has an unhashable value: use tuples, not lists"
            ) from None
        values[name] = vals
    n = math.prod(len(vals) for vals in values.values())
    if n > max_states:
        sizes = " x ".join(f"{len(v)} {k}" for k, v in values.items())
        raise ParameterError(
            f"{n} combinations ({sizes}) > max_states={max_states}: each is an image in the "
            "notebook; give fewer values per slider"
        )
    return Explorer(update, values)


class Explorer:
    """The view returned by :func:`explore`; see the module docstring."""

    def __init__(self, update: Callable[..., Any], sliders: dict[str, list[Any]]):
        self.update = update
        self.sliders = sliders
        self._cache: dict[tuple[Any, ...], State] = {}
        self._widget: Any = None

    @property
    def initial(self) -> dict[str, Any]:
        """The values shown first: each slider's first value."""
        return {k: v[0] for k, v in self.sliders.items()}

    def combinations(self) -> list[dict[str, Any]]:
        """Every combination of the slider values, the last slider varying fastest."""
        names = list(self.sliders)
        return [dict(zip(names, c, strict=True)) for c in itertools.product(*self.sliders.values())]

    def render(self, **values: Any) -> State:
        """The state for ``values`` (one per slider): from the cache, or run ``update`` once."""
        key = tuple(values[k] for k in self.sliders)
        if key not in self._cache:
            self._cache[key] = _render(self.update(**values))
        return self._cache[key]

    def clear(self) -> None:
        """Forget every rendered state (the next render of each runs ``update`` again)."""
        self._cache.clear()

    # -- static page ---------------------------------------------------------------
    def to_html(self) -> str:
        """Every combination rendered, with range inputs and inline JavaScript to swap them."""
        combos = self.combinations()
        states = [self.render(**c) for c in combos]
        uid = "bsx-" + hashlib.sha1(b"".join(s.png for s in states)).hexdigest()[:12]
        first = self.initial  # each slider at its first value
        inputs = [
            f'<label style="display:block">{html.escape(name)} '
            f'<input type="range" min="0" max="{len(vals) - 1}" step="1" value="0" '
            f"data-labels='{html.escape(json.dumps([_label(v) for v in vals]))}'/> "
            f"<span>{html.escape(_label(vals[0]))}</span></label>"
            for name, vals in self.sliders.items()
        ]
        divs = []
        for combo, state in zip(combos, states, strict=True):
            key = "-".join(str(self.sliders[k].index(v)) for k, v in combo.items())
            hidden = "" if combo == first else ' style="display:none"'
            divs.append(f'<div data-state="{key}"{hidden}>{state.html()}</div>')
        held = "; ".join(
            f"{html.escape(k)} = {html.escape(', '.join(_label(v) for v in vals))}"
            for k, vals in self.sliders.items()
        )
        script = (
            "(function(){var r=document.getElementById('UID');"
            "var ins=r.querySelectorAll('input[type=range]');"
            "function show(){var k=[];ins.forEach(function(i){k.push(i.value);"
            "i.nextElementSibling.textContent=JSON.parse(i.dataset.labels)[i.value];});"
            "k=k.join('-');r.querySelectorAll('div[data-state]').forEach(function(d){"
            "d.style.display=d.dataset.state===k?'':'none';});}"
            "ins.forEach(function(i){i.addEventListener('input',show);});})();"
        ).replace("UID", uid)
        return (
            f'<div class="beatsync-explore" id="{uid}">{"".join(inputs)}{"".join(divs)}'
            f'<p style="font-size:smaller">precomputed for: {held}</p>'
            f"<script>{script}</script></div>"
        )

    # -- live view -----------------------------------------------------------------
    def widget(self) -> Any:
        """The ipywidgets view: a SelectionSlider per parameter above an Output."""
        if self._widget is None:
            import ipywidgets as w  # type: ignore[import-untyped]
            from IPython.display import HTML, Image, display

            out = w.Output()
            sliders = {
                k: w.SelectionSlider(
                    options=[(_label(v), v) for v in vals],
                    value=vals[0],
                    description=k,
                    continuous_update=False,
                    style={"description_width": "initial"},
                )
                for k, vals in self.sliders.items()
            }

            def show(_change: Any = None) -> None:
                state = self.render(**{k: s.value for k, s in sliders.items()})
                with out:
                    out.clear_output(wait=True)
                    display(Image(data=state.png, format="png"))
                    if state.extra_html:
                        display(HTML(state.extra_html))

            for s in sliders.values():
                s.observe(show, names="value")
            show()
            self._widget = w.VBox([*sliders.values(), out])
        return self._widget

    def _repr_mimebundle_(self, include: Any = None, exclude: Any = None) -> dict[str, Any]:
        bundle = {"text/plain": f"explore({', '.join(self.sliders)})", "text/html": self.to_html()}
        live = self.widget()._repr_mimebundle_()
        if live:
            bundle.update({k: v for k, v in live.items() if k != "text/plain"})
        return bundle


def _render(result: Any) -> State:
    import matplotlib.pyplot as plt
    from matplotlib.figure import Figure

    fig, extras = (result[0], result[1]) if isinstance(result, tuple) else (result, ())
    if not isinstance(fig, Figure):
        raise ParameterError(
            f"update returned {type(fig).__name__}: return a matplotlib Figure, or (figure, audio)"
        )
    if not isinstance(extras, (list, tuple)):
        extras = (extras,)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=80)
    plt.close(fig)
    return State(buf.getvalue(), "".join(e._repr_html_() or "" for e in extras))


def _label(value: Any) -> str:
    if isinstance(value, tuple):
        return "(" + ", ".join(_label(v) for v in value) + ")"
    if isinstance(value, float):
        return f"{value:g}"
    return str(value)
