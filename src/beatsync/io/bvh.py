"""BVH motion files: read (with a frame-rate override) and write (exact round trip).

The reader is one linear pass: the hierarchy token by token (a joint may be named
``MOTION``), the frames streamed in chunks into a preallocated array (memory near the
values' size). Every malformed line is refused with its number. The writer is
iterative, so any hierarchy the reader accepts (however deep) can be written back.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import ParameterError
from ..motion import Joint, Motion, Skeleton
from ..validation import as_int, check_finite, check_fps
from ._files import atomic_write, check_input_file, check_motion_output

__all__ = ["read_bvh", "write_bvh", "BVH_CHANNELS"]

#: The six channel names a BVH ``CHANNELS`` line may hold (each at most once per joint).
BVH_CHANNELS = ("Xposition", "Yposition", "Zposition", "Xrotation", "Yrotation", "Zrotation")

_FRAMES_RE = re.compile(r"frames\s*:\s*(\S+)", re.IGNORECASE)
_FRAME_TIME_RE = re.compile(r"frame\s+time\s*:\s*(\S+)", re.IGNORECASE)
_CHUNK_ROWS = 4096  # frame lines converted to floats at once


_Lines = Iterator[tuple[int, str]]


def _lines(fh, path: Path) -> _Lines:
    """Numbered UTF-8 lines of a binary file (BOM skipped; ``\\n``, ``\\r\\n`` or ``\\r``
    ends), decoded one at a time so a decoding error names its line."""
    lineno = 0
    for raw in fh:
        if lineno == 0 and raw.startswith(b"\xef\xbb\xbf"):
            raw = raw[3:]
        parts = raw.rstrip(b"\r\n").split(b"\r") if b"\r" in raw else (raw,)
        for part in parts:
            lineno += 1
            try:
                yield lineno, part.decode("utf-8")
            except UnicodeDecodeError as exc:
                raise ParameterError(
                    f"malformed BVH {str(path)!r}: line {lineno} is not UTF-8 text "
                    f"({exc.reason}); is it a BVH file?"
                ) from None


@dataclass
class _Node:
    name: str
    parent: int
    line: int
    is_end_site: bool
    offset: list[float] | None = None
    channels: tuple[str, ...] | None = None


class _HierarchyParser:
    """Token-by-token parser of the HIERARCHY section; stops at the MOTION keyword."""

    def __init__(self, lines: _Lines, path: Path) -> None:
        self.lines = lines
        self.path = path
        self.pending: list[str] = []
        self.lineno = 0

    def err(self, msg: str, line: int | None = None) -> ParameterError:
        where = self.lineno if line is None else line
        return ParameterError(f"malformed BVH {str(self.path)!r}, line {where}: {msg}")

    def next_token(self, what: str) -> str:
        while not self.pending:
            try:
                self.lineno, line = next(self.lines)
            except StopIteration:
                raise self.err(
                    f"file ends where {what} was expected: no MOTION section (truncated?)"
                ) from None
            self.pending = line.split()[::-1]
        return self.pending.pop()

    def numbers(self, count: int, what: str) -> list[str]:
        """The next ``count`` tokens, which must be on the current line."""
        if len(self.pending) < count:
            raise self.err(
                f"{what} needs {count} values on its line, got {len(self.pending)} (truncated?)"
            )
        return [self.pending.pop() for _ in range(count)]

    def parse(self) -> Skeleton:
        first = self.next_token("HIERARCHY")
        if first.upper() != "HIERARCHY":
            raise self.err(f"it starts with {first[:40]!r}, not HIERARCHY (is it a BVH file?)")
        nodes: list[_Node] = []
        stack: list[int] = []
        seen: dict[str, int] = {}  # joint name -> its line: duplicates found in linear time

        def add(node: _Node) -> None:
            if node.name in seen:
                raise self.err(
                    f"duplicate joint name {node.name!r} (first on line {seen[node.name]})",
                    node.line,
                )
            seen[node.name] = node.line
            nodes.append(node)
            stack.append(len(nodes) - 1)

        while True:
            tok = self.next_token("'ROOT', a joint statement or 'MOTION'")
            up = tok.upper()
            if not stack:
                if up == "MOTION":
                    if self.pending:
                        raise self.err(f"unexpected {self.pending[-1]!r} after MOTION")
                    break
                if up != "ROOT":
                    raise self.err(f"expected ROOT or MOTION, got {tok[:40]!r}")
            top = nodes[stack[-1]] if stack else None
            if up in ("ROOT", "JOINT"):
                if up == "ROOT" and stack:
                    raise self.err("ROOT inside another joint (a '}' is missing?)")
                if top is not None and top.is_end_site:
                    raise self.err(f"an End Site cannot hold a {tok}")
                line = self.lineno
                name = self.next_token(f"the name after {tok}")
                if name in ("{", "}"):
                    raise self.err(f"{tok} has no name")
                self.expect_brace(f"{tok} {name}")
                add(_Node(name, stack[-1] if stack else -1, line, False))
            elif up == "END":
                if top is None or top.is_end_site:
                    raise self.err("End Site outside a joint")
                line = self.lineno
                site = self.next_token("'Site' after End")
                if site.upper() != "SITE":
                    raise self.err(f"expected 'End Site', got 'End {site[:40]}'")
                self.expect_brace("End Site")
                add(_Node(f"{top.name}_end", stack[-1], line, True))
            elif up == "OFFSET":
                assert top is not None
                if top.offset is not None:
                    raise self.err(f"a second OFFSET in {self.label(top)}")
                toks = self.numbers(3, "OFFSET")
                for t in toks:
                    if not _is_plain_number(t):
                        raise self.err(f"OFFSET value {t[:40]!r} is not a number")
                off = [float(t) for t in toks]
                if not all(math.isfinite(v) for v in off):
                    raise self.err(
                        f"OFFSET of {self.label(top)} is not finite ({' '.join(toks)}); a bone "
                        "length must be a number"
                    )
                self.line_ends("OFFSET", "an OFFSET has three values")
                top.offset = off
            elif up == "CHANNELS":
                assert top is not None
                if top.is_end_site:
                    raise self.err("an End Site has no CHANNELS")
                if top.channels is not None:
                    raise self.err(f"a second CHANNELS line in {self.label(top)}")
                k = self.numbers(1, "CHANNELS")[0]
                try:
                    count = as_int(k, name="CHANNELS count", minimum=0, text=True)
                except ParameterError as exc:
                    raise self.err(str(exc)) from None
                chans = tuple(self.numbers(count, f"CHANNELS {count}"))
                unknown = [c for c in chans if c not in BVH_CHANNELS]
                if unknown:
                    raise self.err(
                        f"unknown channel {unknown[0][:40]!r} in CHANNELS; channels are "
                        f"{', '.join(BVH_CHANNELS)}"
                    )
                if len(set(chans)) != len(chans):
                    dup = next(c for c in chans if chans.count(c) > 1)
                    raise self.err(f"channel {dup} listed twice in {self.label(top)}")
                self.line_ends(f"CHANNELS {count}", "wrong channel count?")
                top.channels = chans
            elif tok == "}":
                assert top is not None
                if top.offset is None:
                    raise self.err(f"{self.label(top)} has no OFFSET line", top.line)
                if top.channels is None and not top.is_end_site:
                    raise self.err(f"{self.label(top)} has no CHANNELS line", top.line)
                stack.pop()
            elif up == "MOTION":
                raise self.err(
                    f"MOTION section starts before {self.label(top)} is closed "
                    "(a '}' is missing, or the file is truncated?)"
                )
            else:
                raise self.err(f"unexpected token {tok[:40]!r}")
        if not nodes:
            raise self.err("no joints in the hierarchy")
        return Skeleton(
            tuple(
                Joint(n.name, n.parent, np.array(n.offset), n.channels or (), n.is_end_site)
                for n in nodes
            )
        )

    def line_ends(self, what: str, hint: str) -> None:
        if self.pending:
            raise self.err(f"{what} is followed by {self.pending[-1][:40]!r} on its line ({hint})")

    def expect_brace(self, what: str) -> None:
        brace = self.next_token(f"'{{' after {what}")
        if brace != "{":
            raise self.err(f"expected '{{' after {what}, got {brace[:40]!r}")

    @staticmethod
    def label(node: _Node | None) -> str:
        if node is None:
            return "the hierarchy"
        return f"End Site of {node.name[:-4]!r}" if node.is_end_site else f"joint {node.name!r}"


_NUMBER_RE = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?", re.ASCII)


def _is_plain_number(tok: str) -> bool:
    """An ASCII decimal number (no ``_``, no Unicode digits), or nan/inf (refused later)."""
    return _NUMBER_RE.fullmatch(tok) is not None or tok.lower().lstrip("+-") in (
        "nan",
        "inf",
        "infinity",
    )


def _header_value(
    lines: _Lines, pattern: re.Pattern[str], what: str, path: Path
) -> tuple[str, int]:
    """The number on the next non-blank line ``<what> <value>``, and its line number."""
    for lineno, line in lines:
        s = line.strip()
        if not s:
            continue
        match = pattern.fullmatch(s)
        if match is None:
            raise ParameterError(
                f"malformed BVH {str(path)!r}, line {lineno}: expected '{what} <value>', got "
                f"{s[:60]!r}"
            )
        if not _is_plain_number(match.group(1)):
            raise ParameterError(
                f"malformed BVH {str(path)!r}: line {lineno}: {what[:-1]}={match.group(1)!r} is "
                "not a number"
            )
        return match.group(1), lineno
    raise ParameterError(f"malformed BVH {str(path)!r}: no '{what}' line (file truncated?)")


def read_bvh(path: str | os.PathLike[str], *, fps: float | None = None) -> Motion:
    """Read a BVH file; ``fps`` [Hz] overrides ``Frame Time`` (CMU salsa says 120, is 60)."""
    p = check_input_file(path, "BVH")
    try:
        with open(p, "rb") as fh:
            lines = _lines(fh, p)
            skeleton = _HierarchyParser(lines, p).parse()
            n_text, n_line = _header_value(lines, _FRAMES_RE, "Frames:", p)
            try:
                n_declared = as_int(n_text, name=f"line {n_line}: Frames", minimum=0, text=True)
            except ParameterError as exc:
                raise ParameterError(f"malformed BVH {str(p)!r}: {exc}") from None
            frame_time = float(_header_value(lines, _FRAME_TIME_RE, "Frame Time:", p)[0])
            names = skeleton.channel_names()
            if n_declared == 0:
                raise ParameterError(f"BVH {str(p)!r} has no frames (Frames: 0)")
            if not names:
                raise ParameterError(f"BVH {str(p)!r}: the hierarchy defines no channels")
            values = _read_frames(lines, n_declared, len(names), p)
    except OSError as exc:
        raise ParameterError(f"cannot read BVH {str(p)!r}: {exc}") from None
    bad = ~np.isfinite(values)
    if bad.any():  # name the frame and channel, as the other frame errors do
        row, col = (int(i) for i in np.argwhere(bad)[0])
        raise ParameterError(
            f"BVH {str(p)!r}: frame {row + 1} of {values.shape[0]}, channel {names[col]!r} is "
            f"{float(values[row, col])!r} (NaN or infinite; {int(bad.sum())} such value(s) in "
            "all); a motion needs finite numbers: repair or drop those frames"
        )
    if fps is None:
        if not np.isfinite(frame_time) or frame_time <= 0:
            raise ParameterError(
                f"BVH {str(p)!r} has Frame Time {frame_time!r}; give the frame rate with fps="
            )
        rate = 1.0 / frame_time
    else:
        rate = check_fps(fps)
    return Motion(values, rate, names, skeleton, p.stem)


def _read_frames(lines: _Lines, n_declared: int, n_ch: int, path: Path) -> np.ndarray:
    """Stream the frame lines, in chunks read by numpy, into an ``(n_declared, n_ch)`` array.

    A frame line takes at least ``2 * n_ch`` bytes, so a huge declared count in a small
    file allocates no more than the file could fill.
    """
    capacity = min(n_declared, path.stat().st_size // (2 * n_ch) + 1)
    values = np.empty((capacity, n_ch), dtype=np.float64)
    chunk: list[tuple[int, str]] = []  # (line number, text) of lines not yet converted
    stored = row = 0  # frame lines converted into values; frame lines seen

    def flush() -> None:
        nonlocal stored
        values[stored : stored + len(chunk)] = _parse_chunk(chunk, stored, n_ch, path)
        stored += len(chunk)
        chunk.clear()

    for lineno, line in lines:
        if not line.strip():
            continue
        row += 1
        if row > capacity:  # more frame lines than declared: counted, not stored
            continue
        if not line.isascii() or "_" in line:  # Python and numpy read "1_0" and Unicode digits
            _refuse_non_numeric(line.split(), lineno, path)
        chunk.append((lineno, line))
        if len(chunk) == _CHUNK_ROWS:
            flush()
    if chunk:
        flush()
    if row == n_declared and stored != n_declared:
        raise RuntimeError(f"BVH frames stored {stored} of the {row} frames read")
    if row != n_declared:
        raise ParameterError(
            f"BVH {str(path)!r} declares {n_declared} frames but has {row} frame lines "
            "(file truncated or edited?)"
        )
    return values


def _parse_chunk(chunk: list[tuple[int, str]], first_row: int, n_ch: int, path: Path) -> np.ndarray:
    """Frame lines as a ``(len(chunk), n_ch)`` array, or the first bad line named."""
    try:
        block = np.loadtxt([line for _, line in chunk], dtype=np.float64, comments=None, ndmin=2)
        if block.shape == (len(chunk), n_ch):
            return block
    except ValueError:
        pass
    rows = []
    for k, (lineno, line) in enumerate(chunk):
        toks = line.split()
        if len(toks) != n_ch:
            raise ParameterError(
                f"BVH {str(path)!r}, line {lineno}: frame line {first_row + k + 1} has "
                f"{len(toks)} values but the hierarchy defines {n_ch} channels"
            )
        _refuse_non_numeric(toks, lineno, path)
        rows.append(toks)
    return np.array(rows, dtype=np.float64)


def _refuse_non_numeric(toks: list[str], lineno: int, path: Path) -> None:
    bad = next((t for t in toks if not _is_plain_number(t)), None)
    if bad is not None:
        raise ParameterError(
            f"BVH {str(path)!r}, line {lineno}: non-numeric value {bad[:40]!r} in a frame line"
        )


def write_bvh(path: str | os.PathLike[str], motion: Motion) -> Path:
    """Write ``motion`` as BVH (atomic), each value as its shortest exact decimal."""
    check_motion_output(motion, ".bvh", path)
    check_finite(motion.values, name="motion values")
    joints = motion.skeleton.joints
    for j in joints:
        check_finite(j.offset, name=f"OFFSET of joint {j.name!r}")
    children: dict[int, list[int]] = {i: [] for i in range(-1, len(joints))}
    for i, j in enumerate(joints):
        children[j.parent].append(i)
    out: list[str] = ["HIERARCHY"]
    # (joint, depth, opening?) in reverse order: an explicit stack instead of recursion
    todo: list[tuple[int, int, bool]] = [(r, 0, True) for r in reversed(children[-1])]
    while todo:
        i, depth, opening = todo.pop()
        j = joints[i]
        ind = "\t" * depth
        if not opening:
            out.append(f"{ind}}}")
            continue
        if j.is_end_site:
            out.append(f"{ind}End Site")
        else:
            out.append(f"{ind}{'ROOT' if j.parent < 0 else 'JOINT'} {j.name}")
        out.append(f"{ind}{{")
        out.append(f"{ind}\tOFFSET {' '.join(repr(float(v)) for v in j.offset)}")
        if not j.is_end_site:
            out.append(f"{ind}\tCHANNELS {len(j.channels)} {' '.join(j.channels)}")
        todo.append((i, depth, False))
        todo.extend((c, depth + 1, True) for c in reversed(children[i]))
    out += ["MOTION", f"Frames: {motion.n_frames}", f"Frame Time: {1.0 / motion.fps!r}"]
    with atomic_write(path) as fh:
        fh.write("\n".join(out) + "\n")
        for start in range(0, motion.n_frames, _CHUNK_ROWS):
            rows = motion.values[start : start + _CHUNK_ROWS].tolist()
            fh.write("".join(" ".join(map(repr, row)) + "\n" for row in rows))
    return Path(path)
