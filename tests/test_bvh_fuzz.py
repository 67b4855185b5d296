"""Fuzz of the BVH reader against an independent reference parser.

A few hundred files are made by seeded mutations of a short bundled BVH (CMU walk
007_12, cut to its first frames): characters, numbers, lines, header fields and
joint names changed, deleted, duplicated or swapped; byte-order marks, CRLF line
ends, tabs and invalid UTF-8. Every file must either be refused with a
``ParameterError`` by both parsers, or be read by both to the same skeleton, values
and frame rate. The reference below is written from the format's grammar, on the
whole text at once and recursively, sharing no code with ``beatsync.io.bvh``.
"""

from __future__ import annotations

import math
import random
import re
from dataclasses import dataclass

import numpy as np
import pytest

from beatsync import datasets, io
from beatsync.errors import ParameterError

N_CASES = 400
SEED = 20261127
N_FRAMES = 5  # frames kept from the bundled file: the hierarchy is what gets fuzzed most

CHANNEL_NAMES = {"Xposition", "Yposition", "Zposition", "Xrotation", "Yrotation", "Zrotation"}
NUMBER = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?|[+-]?(nan|inf|infinity)", re.I | re.A)


class Refused(Exception):
    """The reference parser refuses the file."""


@dataclass
class RefBvh:
    names: list[str]
    parents: list[int]
    offsets: list[list[float]]
    channels: list[tuple[str, ...]]
    end_sites: list[bool]
    values: np.ndarray
    frame_time: float


def _number(tok: str) -> float:
    if not NUMBER.fullmatch(tok):
        raise Refused(f"not a number: {tok!r}")
    return float(tok)


def reference_parse(data: bytes) -> RefBvh:
    """Parse BVH bytes from the grammar; raise Refused for anything malformed."""
    if data.startswith(b"\xef\xbb\xbf"):
        data = data[3:]
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise Refused("not UTF-8") from None
    lines = re.split(r"\r\n|\r|\n", text)
    # (line index, token) pairs of the whole file; a token never spans lines
    toks = [(i, t) for i, line in enumerate(lines) for t in line.split()]
    pos = 0
    ref = RefBvh([], [], [], [], [], np.empty(0), 0.0)

    def take() -> tuple[int, str]:
        nonlocal pos
        if pos >= len(toks):
            raise Refused("truncated")
        pos += 1
        return toks[pos - 1]

    def rest_of_line(line: int, n: int) -> list[str]:
        """The next n tokens, all on ``line``, and nothing after them on it."""
        out = [take() for _ in range(n)]
        if any(li != line for li, _ in out):
            raise Refused("values split over lines")
        if pos < len(toks) and toks[pos][0] == line:
            raise Refused("extra values on a line")
        return [t for _, t in out]

    def joint(name: str, parent: int, end_site: bool) -> None:
        if name in ref.names:
            raise Refused("duplicate joint name")
        me = len(ref.names)
        ref.names.append(name)
        ref.parents.append(parent)
        ref.offsets.append(None)
        ref.channels.append(None)
        ref.end_sites.append(end_site)
        if take()[1] != "{":
            raise Refused("no brace")
        while True:
            line, tok = take()
            key = tok.upper()
            if tok == "}":
                break
            if key == "OFFSET":
                if ref.offsets[me] is not None:
                    raise Refused("second OFFSET")
                off = [_number(t) for t in rest_of_line(line, 3)]
                if not all(math.isfinite(v) for v in off):
                    raise Refused("non-finite OFFSET")
                ref.offsets[me] = off
            elif key == "CHANNELS" and not end_site:
                if ref.channels[me] is not None:
                    raise Refused("second CHANNELS")
                if pos >= len(toks) or toks[pos][0] != line:
                    raise Refused("no channel count")
                count = _number(take()[1])
                if not math.isfinite(count) or count != int(count) or count < 0:
                    raise Refused("bad channel count")
                chans = tuple(rest_of_line(line, int(count)))
                if not set(chans) <= CHANNEL_NAMES or len(set(chans)) != len(chans):
                    raise Refused("bad channels")
                ref.channels[me] = chans
            elif key == "JOINT" and not end_site:
                child = take()[1]
                if child in ("{", "}"):
                    raise Refused("nameless joint")
                joint(child, me, False)
            elif key == "END" and not end_site:
                if take()[1].upper() != "SITE":
                    raise Refused("End without Site")
                joint(f"{name}_end", me, True)
            else:
                raise Refused(f"unexpected {tok!r}")
        if ref.offsets[me] is None or (ref.channels[me] is None and not end_site):
            raise Refused("missing OFFSET or CHANNELS")

    if take()[1].upper() != "HIERARCHY":
        raise Refused("no HIERARCHY")
    while True:
        line, tok = take()
        if tok.upper() == "MOTION":
            if pos < len(toks) and toks[pos][0] == line:
                raise Refused("text after MOTION")
            break
        if tok.upper() != "ROOT":
            raise Refused("expected ROOT")
        name = take()[1]
        if name in ("{", "}"):
            raise Refused("nameless root")
        joint(name, -1, False)
    if not ref.names:
        raise Refused("no joints")
    after = [ln.strip() for ln in lines[line + 1 :]]
    after = [ln for ln in after if ln]
    if len(after) < 2:
        raise Refused("no header")
    m_frames = re.fullmatch(r"(?i)frames\s*:\s*(\S+)", after[0])
    m_time = re.fullmatch(r"(?i)frame\s+time\s*:\s*(\S+)", after[1])
    if not (m_frames and m_time):
        raise Refused("bad header")
    n = _number(m_frames.group(1))
    if not math.isfinite(n) or n != int(n) or n < 1:
        raise Refused("bad frame count")
    ref.frame_time = _number(m_time.group(1))
    if not (math.isfinite(ref.frame_time) and ref.frame_time > 0):
        raise Refused("bad frame time")
    n_ch = sum(len(c) for c in ref.channels if c)
    rows = [ln.split() for ln in after[2:]]
    if n_ch == 0 or len(rows) != n or any(len(r) != n_ch for r in rows):
        raise Refused("frame lines do not match")
    ref.values = np.array([[_number(t) for t in r] for r in rows], dtype=np.float64)
    if not np.all(np.isfinite(ref.values)):
        raise Refused("non-finite values")
    if 1.0 / ref.frame_time < 1.0:
        raise Refused("frame rate below 1 Hz")
    # forward kinematics must not overflow: along each chain, the offsets' and the
    # translations' |x| + |y| + |z| summed (a bound on the distance from the origin),
    # times 2 sqrt(3) (a coordinate of a difference of two positions), is finite
    col, reach = 0, []
    for i, chans in enumerate(ref.channels):
        size = sum(abs(v) for v in ref.offsets[i])
        for c in chans or ():
            if c.endswith("position"):
                size += max(abs(float(v)) for v in ref.values[:, col])
            col += 1
        reach.append(size + (reach[ref.parents[i]] if ref.parents[i] >= 0 else 0.0))
    if not math.isfinite(2 * math.sqrt(3) * max(reach)):
        raise Refused("forward kinematics overflows")
    return ref


# ---------------------------------------------------------------- the base file


def _base_text() -> str:
    text = datasets.path("motion/cmu_walk_modern/007_12.bvh").read_text()
    head, _, motion = text.partition("\nMOTION\n")
    rows = motion.splitlines()
    return (
        f"{head}\nMOTION\nFrames: {N_FRAMES}\n{rows[1]}\n"
        + "\n".join(rows[2 : 2 + N_FRAMES])
        + "\n"
    )


# ---------------------------------------------------------------- mutations

_CHARS = list("0123456789 .-+e\n\t{}_xn") + ["\u0663", "\r"]
_TOKENS = [
    "nan",
    "inf",
    "-inf",
    "1e400",
    "1e308",
    "-2e307",
    "",
    "1.2.3",
    "-0",
    "+5",
    ".5",
    "5.",
    "1_0",
    "0x1",
    "{",
    "}",
]


def _mutate(text: str, r: random.Random) -> bytes:
    op = r.randrange(18)
    try:
        return _apply(op, text, r)
    except (IndexError, ValueError):  # nothing to pick from (an earlier mutation removed it)
        return _apply(1, text, r)


def _apply(op: int, text: str, r: random.Random) -> bytes:
    lines = text.split("\n")
    if op == 0:  # delete a character
        i = r.randrange(len(text))
        text = text[:i] + text[i + 1 :]
    elif op == 1:  # insert a character
        i = r.randrange(len(text))
        text = text[:i] + r.choice(_CHARS) + text[i:]
    elif op == 2:  # replace a character
        i = r.randrange(len(text))
        text = text[:i] + r.choice(_CHARS) + text[i + 1 :]
    elif op == 3:  # delete a line
        del lines[r.randrange(len(lines))]
        text = "\n".join(lines)
    elif op == 4:  # duplicate a line
        i = r.randrange(len(lines))
        lines.insert(i, lines[i])
        text = "\n".join(lines)
    elif op == 5:  # swap two adjacent lines
        i = r.randrange(len(lines) - 1)
        lines[i], lines[i + 1] = lines[i + 1], lines[i]
        text = "\n".join(lines)
    elif op == 6:  # replace a number with another token
        spans = [m.span() for m in re.finditer(r"-?\d+\.\d+", text)]
        a, b = r.choice(spans)
        text = text[:a] + r.choice(_TOKENS) + text[b:]
    elif op == 7:  # join two lines
        i = r.randrange(len(lines) - 1)
        lines[i : i + 2] = [lines[i] + " " + lines[i + 1]]
        text = "\n".join(lines)
    elif op == 8:  # split a line at a space
        spaces = [m.start() for m in re.finditer(" ", text)]
        i = r.choice(spaces)
        text = text[:i] + "\n" + text[i + 1 :]
    elif op == 9:  # truncate
        text = text[: r.randrange(len(text))]
    elif op == 10:  # frame count
        new = r.choice([N_FRAMES - 1, N_FRAMES + 1, 0, -1, 10**12, "5.0", "five", "2.5"])
        text = text.replace(f"Frames: {N_FRAMES}", f"Frames: {new}")
    elif op == 11:  # frame time
        new = r.choice(["0", "-0.01", "nan", "x", "0.001", "2", "1e-3", "0.0083333"])
        text = re.sub(r"Frame Time: \S+", f"Frame Time: {new}", text)
    elif op == 12:  # encodings and whitespace of a valid file
        text = r.choice(
            [
                "\ufeff" + text,
                text.replace("\n", "\r\n"),
                text.replace("\n", "\r"),
                text.replace(" ", "\t"),
                text.replace("Frame Time:", "Frame  Time:"),
                text.replace("    ", ""),
                text + "\n\n\n",
            ]
        )
    elif op == 13:  # rename a joint: to another joint's name, or to a keyword-like name
        names = re.findall(r"JOINT (\S+)", text)
        old = r.choice(names)
        new = r.choice([r.choice(names), "MOTION", "MOTIONx", "End", "{", "ROOT", old + "_x"])
        text = text.replace(f"JOINT {old}\n", f"JOINT {new}\n", 1)
    elif op == 14:  # channel count
        m = r.choice(list(re.finditer(r"CHANNELS (\d)", text)))
        new = r.choice(["0", "2", "4", "6", "-3", "x", "3.0"])
        text = text[: m.start(1)] + new + text[m.end(1) :]
    elif op == 15:  # a channel name repeated or unknown
        m = r.choice(list(re.finditer(r"[XYZ]rotation", text)))
        new = r.choice(["Xrotation", "Yrotation", "Zrotation", "Wrotation", "xrotation"])
        text = text[: m.start()] + new + text[m.end() :]
    elif op == 16:  # a line's values: one removed here, one added there (the total is kept)
        frame_lines = [i for i, ln in enumerate(lines) if ln[:1] in "-0123456789" and " " in ln]
        i, j = sorted(r.sample(frame_lines, 2))
        lines[i] = lines[i].rsplit(" ", 1)[0]
        lines[j] = lines[j] + " 0.5"
        text = "\n".join(lines)
    else:  # invalid UTF-8 byte
        data = text.encode()
        i = r.randrange(len(data))
        return data[:i] + bytes([r.choice([0xFF, 0xC3, 0x80])]) + data[i:]
    return text.encode("utf-8")


def _cases() -> list[bytes]:
    base = _base_text()
    r = random.Random(SEED)
    out = [base.encode()]
    while len(out) < N_CASES:
        data = _mutate(base, r)
        if r.random() < 0.25:  # a second mutation on top
            try:
                data = _mutate(data.decode("utf-8"), r)
            except UnicodeDecodeError:
                pass
        out.append(data)
    return out


def test_reference_parser_reads_the_base_file():
    ref = reference_parse(_base_text().encode())
    m = io.read_bvh(datasets.path("motion/cmu_walk_modern/007_12.bvh"))
    np.testing.assert_array_equal(ref.values, m.values[:N_FRAMES])
    assert ref.names == [j.name for j in m.skeleton.joints]


def test_fuzzed_bvh_refused_or_equal_to_reference(tmp_path):
    accepted = refused = 0
    path = tmp_path / "case.bvh"
    for k, data in enumerate(_cases()):
        path.write_bytes(data)
        try:
            ref = reference_parse(data)
        except Refused as exc:
            ref, why = None, str(exc)
        try:
            m = io.read_bvh(path)
        except ParameterError as exc:
            assert ref is None, f"case {k}: refused a file the reference reads: {exc}"
            refused += 1
            continue
        assert ref is not None, f"case {k}: read a file the reference refuses ({why})"
        joints = m.skeleton.joints
        assert [j.name for j in joints] == ref.names, f"case {k}"
        assert [j.parent for j in joints] == ref.parents, f"case {k}"
        assert [j.is_end_site for j in joints] == ref.end_sites, f"case {k}"
        assert [tuple(j.channels) for j in joints] == [c or () for c in ref.channels]
        np.testing.assert_array_equal(np.array([j.offset for j in joints]), ref.offsets)
        np.testing.assert_array_equal(m.values, ref.values, err_msg=f"case {k}")
        assert m.fps == 1.0 / ref.frame_time, f"case {k}"
        accepted += 1
    # both outcomes are exercised
    assert accepted >= N_CASES // 10 and refused >= N_CASES // 2, (accepted, refused)


@pytest.mark.parametrize("k", [0, 1])
def test_mutations_are_seeded(k):
    assert _cases()[k] == _cases()[k]


@pytest.mark.parametrize(
    "old, new, named",
    [
        ("OFFSET", "OFFSET 1e308 0 0", "1e+308"),  # one huge bone offset
        (None, "1e308", "Xposition value 1e+308"),  # a huge root translation in a frame
    ],
)
def test_an_overflowing_offset_or_translation_is_refused_by_both(tmp_path, old, new, named):
    text = _base_text()
    if old is None:  # the first frame's first value (the root's Xposition)
        head, _, frames = text.partition("Frame Time:")
        time_line, first, *rest = frames.split("\n")
        text = "\n".join(
            [head + "Frame Time:" + time_line, first.replace(first.split()[0], new, 1), *rest]
        )
    else:
        first = text.index(old, text.index("JOINT"))
        end = text.index("\n", first)
        text = text[:first] + new + text[end:]
    with pytest.raises(Refused, match="overflows"):
        reference_parse(text.encode())
    path = tmp_path / "huge.bvh"
    path.write_text(text)
    with pytest.raises(ParameterError, match=re.escape(named)):
        io.read_bvh(path)
