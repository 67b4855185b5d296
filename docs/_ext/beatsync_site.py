"""Sphinx extension of the beatsync site: the notebooks in the source tree, optional pages.

The notebooks live in ``notebooks/`` (the reproduction notebooks) and
``notebooks/tutorials/`` (the tutorials), outside ``docs/``, because ``make reproduce``,
nbval and JupyterLab use them there. Sphinx reads only files under its source folder,
so at the start of every build they are copied into ``docs/notebooks/`` (ignored by
git). A copy is written only when the notebook differs from it, with the notebook's
own modification time, so that an unchanged notebook is not read again by an
incremental build; a copy whose notebook is gone is removed, and so is its page in
the built site (Sphinx leaves the pages of removed documents behind).

:func:`cli_parser` is the program's parser with its help texts escaped for
reStructuredText, which sphinx-argparse parses them as: the help is plain text
(``*_angle``, ``essentia-*``) and must read on the page as it does in ``--help``.

The ``globtoctree`` directive is Sphinx's ``toctree`` with ``:glob:`` whose patterns
may match nothing yet (a page still to be written, a folder of tutorials still
empty): such a pattern is left out instead of warned about, so the site builds with
warnings as errors at every stage of the project. Sphinx reads a page with a glob
toctree again whenever a page is added or removed, so a new page appears in it
without a clean build.
"""

from __future__ import annotations

import argparse
import filecmp
import re
import shutil
from pathlib import Path

from docutils.statemachine import StringList
from sphinx.application import Sphinx
from sphinx.config import Config
from sphinx.directives.other import TocTree, glob_re
from sphinx.util import docname_join
from sphinx.util.matching import patfilter

#: source folder (relative to the repository) -> folder under docs/
NOTEBOOK_FOLDERS = {"notebooks": "notebooks", "notebooks/tutorials": "notebooks/tutorials"}


def copy_notebooks(srcdir: Path) -> list[Path]:
    """Mirror the committed notebooks into ``srcdir/notebooks``; return the copies."""
    root = srcdir.parent
    copies = []
    for source, target in NOTEBOOK_FOLDERS.items():
        out = srcdir / target
        out.mkdir(parents=True, exist_ok=True)
        wanted = set()
        for notebook in sorted((root / source).glob("*.ipynb")):
            copy = out / notebook.name
            wanted.add(copy.name)
            if not copy.exists() or not filecmp.cmp(notebook, copy, shallow=False):
                shutil.copy2(notebook, copy)
            copies.append(copy)
        for stale in out.glob("*.ipynb"):
            if stale.name not in wanted:
                stale.unlink()
    return copies


_RST_SPECIAL = re.compile(r"([\\*`|_])")


def _plain(text: str | None) -> str | None:
    return None if text is None else _RST_SPECIAL.sub(r"\\\1", text)


def cli_parser() -> argparse.ArgumentParser:
    """``beatsync.cli.build_parser()`` with every help text escaped for reStructuredText."""
    from beatsync.cli import build_parser

    def escape(parser: argparse.ArgumentParser) -> None:
        parser.description = _plain(parser.description)
        parser.epilog = _plain(parser.epilog)
        for action in parser._actions:
            if isinstance(action.help, str) and action.help != argparse.SUPPRESS:
                action.help = _plain(action.help)
            if isinstance(action, argparse._SubParsersAction):
                for choice in action._choices_actions:
                    choice.help = _plain(choice.help)
                for sub in dict.fromkeys(action.choices.values()):
                    escape(sub)

    parser = build_parser()
    escape(parser)
    return parser


class GlobTocTree(TocTree):
    """``toctree`` with ``:glob:`` set, leaving out the patterns that match no page."""

    def run(self):
        self.options["glob"] = None
        return super().run()

    def parse_content(self, toctree) -> None:
        docname = self.env.current_document.docname
        others = self.env.found_docs - {docname}
        kept = StringList()
        for offset, line in enumerate(self.content):
            entry = line.strip()
            if glob_re.match(entry) and not patfilter(others, docname_join(docname, entry)):
                continue
            kept.append(line, *self.content.info(offset))
        self.content = kept
        super().parse_content(toctree)


def _on_config_inited(app: Sphinx, config: Config) -> None:
    copy_notebooks(Path(app.srcdir))


def _on_build_finished(app: Sphinx, exc: Exception | None) -> None:
    if exc is not None or app.builder.format != "html":
        return
    out = Path(app.outdir)
    for page in (out / "notebooks").rglob("*.html"):
        if page.relative_to(out).with_suffix("").as_posix() not in app.env.found_docs:
            page.unlink()


def setup(app: Sphinx) -> dict[str, object]:
    app.connect("config-inited", _on_config_inited)
    app.connect("build-finished", _on_build_finished)
    app.add_directive("globtoctree", GlobTocTree)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
