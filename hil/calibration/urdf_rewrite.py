"""A URDF with some joints' origins changed and every other byte kept: the calibrated-URDF writer.

`hil export --format urdf` for an arm read from a URDF must give back the user's own file —
links, inertias, meshes, limits, comments, whitespace, attribute order, quoting, the XML declaration —
with only the calibrated joint origins changed, so that whatever else reads that file (a simulator, a
planner, a ROS launch) keeps working on it. Re-serialising a parsed tree cannot promise that (it drops
comments, reorders or requotes attributes, rewrites the declaration), so the file is never
re-serialised: the stdlib's expat parser only *locates* the `<joint>` elements and their `<origin>` by
byte offset, and the new `xyz`/`rpy` values are spliced into the original bytes.

Numbers are written with ``repr`` (the shortest text that reads back to the same double), so a round
trip through the file is exact. An attribute a joint's `<origin>` lacks is inserted after its last
attribute; a joint with no `<origin>` gets one as its first child, indented like the child after it.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from xml.parsers import expat

from hil.errors import InputError

Triple = tuple[float, float, float]


@dataclass(frozen=True)
class Origin:
    """A URDF origin: `xyz` (m) and `rpy` (rad, R = Rz(yaw)·Ry(pitch)·Rx(roll)) in the parent link's frame."""

    xyz: Triple
    rpy: Triple


@dataclass(frozen=True)
class Span:
    """Bytes [start, end) of the document."""

    start: int
    end: int


@dataclass(frozen=True)
class StartTag:
    """Where a start tag's pieces are: each attribute value's span (without quotes), the point after its
    last attribute (where a new one goes), the end of the tag, and the quote its attributes use."""

    start: int
    end: int
    values: dict[str, Span]
    insert_at: int
    quote: bytes


@dataclass(frozen=True)
class JointSite:
    """One top-level `<joint>` of a URDF: its name, type, parent and child links and line, its start
    tag, its `<origin>`'s start tag (None when it has none), where its first child element starts, and
    the origin it declares."""

    name: str
    kind: str
    parent: str
    child: str
    line: int
    tag: StartTag
    origin_tag: StartTag | None
    first_child: int | None
    origin: Origin


_NAME_END = re.compile(rb"[\s/>]")
_SPACE = re.compile(rb"\s*")
_ATTR_NAME = re.compile(rb"[^\s=/>]+")


def _start_tag(data: bytes, start: int, source: str, line: int) -> StartTag:
    """The pieces of the start tag at byte `start` (expat has checked it is well formed)."""
    if data[start:start + 1] != b"<":
        raise InputError(f"{source}:{line}: cannot locate the element's bytes (only UTF-8 and other "
                         "ASCII-compatible encodings are supported)")
    m = _NAME_END.search(data, start + 1)
    assert m is not None  # expat accepted the element, so its tag ends
    pos = insert_at = m.start()
    values: dict[str, Span] = {}
    quote = b'"'
    while True:
        pos = _SPACE.match(data, pos).end()  # type: ignore[union-attr]
        if data[pos:pos + 1] == b">":
            return StartTag(start, pos + 1, values, insert_at, quote)
        if data[pos:pos + 2] == b"/>":
            return StartTag(start, pos + 2, values, insert_at, quote)
        name_match = _ATTR_NAME.match(data, pos)
        assert name_match is not None
        name = name_match.group().decode("ascii", errors="replace")
        pos = _SPACE.match(data, name_match.end()).end()  # type: ignore[union-attr]
        assert data[pos:pos + 1] == b"="
        pos = _SPACE.match(data, pos + 1).end()  # type: ignore[union-attr]
        quote = data[pos:pos + 1]
        close = data.index(quote, pos + 1)
        values[name] = Span(pos + 1, close)
        pos = insert_at = close + 1


def _triple(text: str | None, source: str, line: int, field: str) -> Triple:
    """An `xyz`/`rpy` attribute's three numbers; a missing attribute is zero, as URDF says."""
    if text is None:
        return (0.0, 0.0, 0.0)
    parts = text.split()
    try:
        values = tuple(float(p) for p in parts)
    except ValueError:
        values = ()
    if len(values) != 3 or not all(math.isfinite(v) for v in values):
        raise InputError(f"{source}:{line}: origin {field}={text!r} is not three finite numbers")
    return values  # type: ignore[return-value]


def locate_joints(data: bytes, source: str = "URDF") -> dict[str, JointSite]:
    """Every top-level `<joint>` of the URDF `data` by name, with the byte positions a rewrite needs.

    Only the `<robot>` element's own `<joint>` children are joints: `<transmission>` and `<gazebo>`
    blocks name joints too, and must not be touched. `source` names the file in errors.
    """
    parser = expat.ParserCreate()
    stack: list[str] = []
    found: dict[str, JointSite] = {}
    current: dict[str, object] = {}

    def start(name: str, attrs: dict[str, str]) -> None:
        stack.append(name)
        depth = len(stack)
        line = parser.CurrentLineNumber
        if depth == 1 and name != "robot":
            raise InputError(f"{source}:{line}: the root element is <{name}>, not <robot>: not a URDF")
        if depth == 2 and name == "joint":
            joint = attrs.get("name")
            if not joint:
                raise InputError(f"{source}:{line}: a <joint> without a name")
            if joint in found:
                raise InputError(f"{source}:{line}: joint {joint!r} is declared twice")
            current.clear()
            current.update(name=joint, kind=attrs.get("type", ""), parent="", child="", line=line,
                           tag=_start_tag(data, parser.CurrentByteIndex, source, line),
                           origin_tag=None, first_child=None, origin=Origin((0.0,) * 3, (0.0,) * 3))
        elif depth == 3 and stack[1] == "joint" and current:
            if current["first_child"] is None:
                current["first_child"] = parser.CurrentByteIndex
            if name in ("parent", "child"):
                current[name] = attrs.get("link", "")
            if name == "origin":
                if current["origin_tag"] is not None:
                    raise InputError(f"{source}:{line}: joint {current['name']!r} has two <origin> elements")
                current["origin_tag"] = _start_tag(data, parser.CurrentByteIndex, source, line)
                current["origin"] = Origin(_triple(attrs.get("xyz"), source, line, "xyz"),
                                           _triple(attrs.get("rpy"), source, line, "rpy"))

    def end(name: str) -> None:
        if len(stack) == 2 and name == "joint" and current:
            site = JointSite(**current)  # type: ignore[arg-type]
            found[site.name] = site
            current.clear()
        stack.pop()

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    try:
        parser.Parse(data, True)
    except expat.ExpatError as exc:
        reason = expat.ErrorString(exc.code)
        raise InputError(f"{source}:{exc.lineno}: not well-formed XML ({reason})") from None
    return found


def format_triple(values: Sequence[float]) -> str:
    """Three numbers as URDF writes them, each with ``repr`` so it reads back to the same double."""
    numbers = [float(v) for v in values]
    if len(numbers) != 3 or not all(math.isfinite(v) for v in numbers):
        raise ValueError(f"an origin needs three finite numbers, got {values!r}")
    return " ".join(repr(v + 0.0) for v in numbers)  # + 0.0: no "-0.0"


def rewrite_joint_origins(data: bytes, origins: Mapping[str, Origin], source: str = "URDF") -> bytes:
    """`data` (a URDF's bytes) with the origin of each joint named in `origins` set to its value, and
    every other byte unchanged; an InputError naming `source` and the line when the file is not a
    URDF or names a joint twice, or when `origins` names a joint the file does not have."""
    sites = locate_joints(data, source)
    missing = sorted(set(origins) - set(sites))
    if missing:
        raise InputError(f"{source}: no joint named {', '.join(repr(m) for m in missing)} "
                         f"(its joints: {', '.join(sites)})")
    edits: list[tuple[int, int, bytes]] = []
    for name, origin in origins.items():
        site = sites[name]
        if site.origin_tag is None:
            edits.append(_new_origin_element(data, site, origin, source))
        else:
            edits.extend(_attribute_edits(site.origin_tag, origin))
    out = []
    pos = 0
    for start, end, text in sorted(edits, key=lambda e: (e[0], e[1])):  # stable: xyz before rpy
        out += [data[pos:start], text]
        pos = end
    out.append(data[pos:])
    return b"".join(out)


def rewrite_joint_origins_text(text: str, origins: Mapping[str, Origin], source: str = "URDF") -> str:
    """`rewrite_joint_origins` on a URDF held as text (UTF-8 in between)."""
    return rewrite_joint_origins(text.encode("utf-8"), origins, source).decode("utf-8")


def _values(origin: Origin) -> dict[str, bytes]:
    """The new `xyz` and `rpy` attribute values."""
    return {"xyz": format_triple(origin.xyz).encode(), "rpy": format_triple(origin.rpy).encode()}


def _attribute_edits(tag: StartTag, origin: Origin) -> list[tuple[int, int, bytes]]:
    """Splices that set an existing `<origin>`'s `xyz` and `rpy`, inserting the one it lacks after its
    last attribute, in the quote its other attributes use."""
    new = _values(origin)
    edits = []
    for key in ("xyz", "rpy"):
        span = tag.values.get(key)
        if span is None:
            edits.append((tag.insert_at, tag.insert_at,
                          b" " + key.encode() + b"=" + tag.quote + new[key] + tag.quote))
        else:
            edits.append((span.start, span.end, new[key]))
    return edits


def _new_origin_element(data: bytes, site: JointSite, origin: Origin, source: str) -> tuple[int, int, bytes]:
    """The splice that gives a joint without `<origin>` one, as its first child, followed by the same
    whitespace that stood before that child (so the file keeps its indentation)."""
    if site.first_child is None:
        raise InputError(f"{source}:{site.line}: joint {site.name!r} has no child elements "
                         "(a URDF joint needs <parent> and <child>)")
    indent_start = site.first_child
    while indent_start > site.tag.end and data[indent_start - 1:indent_start] in (b" ", b"\t", b"\n", b"\r"):
        indent_start -= 1
    indent = data[indent_start:site.first_child]
    new = _values(origin)
    q = site.tag.quote
    element = b"<origin xyz=" + q + new["xyz"] + q + b" rpy=" + q + new["rpy"] + q + b"/>"
    return (site.first_child, site.first_child, element + indent)
