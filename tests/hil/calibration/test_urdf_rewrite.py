"""The URDF origin splicer: only the joint origins change, byte for byte, on real arms' URDFs and on
the corner cases (a missing origin or attribute, other quotes, a transmission naming the joint)."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pytest

from hil.calibration.urdf_rewrite import (
    Origin,
    format_triple,
    locate_joints,
    rewrite_joint_origins,
    rewrite_joint_origins_text,
)
from hil.errors import InputError
from tests.hil.robot_urdfs import ARMS
from tests.hil.robot_urdfs import arm as arm_urdf


def _random_origin(rng: np.random.Generator) -> Origin:
    return Origin(tuple(rng.uniform(-0.5, 0.5, 3)), tuple(rng.uniform(-3.0, 3.0, 3)))  # type: ignore[arg-type]


def _cut(data: bytes, spans: list[tuple[int, int]]) -> bytes:
    out, pos = [], 0
    for start, end in sorted(spans):
        out.append(data[pos:start])
        pos = end
    return b"".join(out) + data[pos:]


@pytest.mark.parametrize("arm", sorted(ARMS))
def test_every_byte_outside_the_changed_origins_is_kept(arm: str) -> None:
    """Every joint's origin changed on a real URDF: outside the `<origin>` tags the file is the same
    bytes; inside them everything but the two values is; the values read back exactly."""
    data = arm_urdf(arm)[0].read_bytes()
    rng = np.random.default_rng(7)
    before = locate_joints(data)
    assert len(before) == len(ET.fromstring(data).findall("joint"))  # transmissions' <joint>s are not joints
    origins = {name: _random_origin(rng) for name in before}
    out = rewrite_joint_origins(data, origins, arm)
    after = locate_joints(out)
    assert list(after) == list(before)
    tags_before = [(s.origin_tag.start, s.origin_tag.end) for s in before.values()]  # type: ignore[union-attr]
    tags_after = [(s.origin_tag.start, s.origin_tag.end) for s in after.values()]  # type: ignore[union-attr]
    assert _cut(out, tags_after) == _cut(data, tags_before)
    for name in before:
        old, new = before[name].origin_tag, after[name].origin_tag
        assert old is not None and new is not None
        spans_old = [(v.start, v.end) for k, v in old.values.items() if k in ("xyz", "rpy")]
        spans_new = [(v.start, v.end) for k, v in new.values.items() if k in ("xyz", "rpy")]
        assert len(spans_old) == 2
        assert _cut(out[new.start:new.end], [(a - new.start, b - new.start) for a, b in spans_new]) == \
            _cut(data[old.start:old.end], [(a - old.start, b - old.start) for a, b in spans_old])
        assert after[name].origin == Origin(tuple(float(v) for v in origins[name].xyz),  # type: ignore[arg-type]
                                            tuple(float(v) for v in origins[name].rpy))  # type: ignore[arg-type]


def test_a_joint_named_in_a_transmission_is_changed_only_in_its_joint() -> None:
    data = arm_urdf("ur5")[0].read_bytes()
    assert data.count(b'<joint name="shoulder_pan_joint"') == 2  # the joint and its transmission's
    out = rewrite_joint_origins(data, {"shoulder_pan_joint": Origin((0.0, 0.0, 0.1), (0.0, 0.0, 0.5))})
    assert out.count(b'xyz="0.0 0.0 0.1"') == 1 and out.count(b'rpy="0.0 0.0 0.5"') == 1
    assert len(out) - len(data) == len(b"0.0 0.0 0.1") + len(b"0.0 0.0 0.5") - len(b"0.0 0.0 0.089159") \
        - len(b"0.0 0.0 0.0")


SMALL = """<?xml version='1.0'?>
<!-- a comment with <joint name="j1"> in it -->
<robot name='r'>
  <link name='a'/><link name='b'/><link name='c'/><link name='d'/>
  <joint name='j1' type='revolute'>
    <parent link='a'/>
    <child link='b'/>
    <axis xyz='0 0 1'/>
  </joint>
  <joint type="fixed" name="j2">
    <origin xyz="1 2 3"   />
    <parent link="b"/><child link="c"/>
  </joint>
  <joint name="j3" type="fixed"><origin/><parent link="c"/><child link="d"/></joint>
</robot>
"""


def test_a_missing_origin_is_inserted_as_the_first_child_indented_like_the_next() -> None:
    out = rewrite_joint_origins_text(SMALL, {"j1": Origin((0.5, 0.0, -0.25), (0.0, 1e-17, 3.0))})
    assert out == SMALL.replace(
        "<joint name='j1' type='revolute'>\n    <parent",
        "<joint name='j1' type='revolute'>\n    <origin xyz='0.5 0.0 -0.25' rpy='0.0 1e-17 3.0'/>"
        "\n    <parent")


def test_a_missing_attribute_is_inserted_after_the_last_one() -> None:
    out = rewrite_joint_origins_text(SMALL, {"j2": Origin((1.0, 2.0, 3.5), (0.1, 0.2, 0.3)),
                                             "j3": Origin((0.0, 0.0, 1.0), (0.0, 0.0, 0.0))})
    expected = SMALL.replace('<origin xyz="1 2 3"   />', '<origin xyz="1.0 2.0 3.5" rpy="0.1 0.2 0.3"   />')
    expected = expected.replace("<origin/>", '<origin xyz="0.0 0.0 1.0" rpy="0.0 0.0 0.0"/>')
    assert out == expected


def test_numbers_are_written_so_they_read_back_to_the_same_double() -> None:
    rng = np.random.default_rng(3)
    values = rng.normal(size=(1000, 3)) * 10.0 ** rng.integers(-15, 3, size=(1000, 1))
    for v in values:
        assert np.array_equal(np.array([float(t) for t in format_triple(v).split()]), v)
    assert format_triple([-0.0, 0.0, 1.0]) == "0.0 0.0 1.0"
    with pytest.raises(ValueError, match="three finite"):
        format_triple([0.0, float("nan"), 1.0])


@pytest.mark.parametrize(("text", "message"), [
    ("<robot><joint name='j'>", r"^x\.urdf:1: not well-formed XML"),
    ("<sdf/>", r"^x\.urdf:1: the root element is <sdf>, not <robot>"),
    ("<robot>\n<joint name='j'><parent link='a'/></joint>\n<joint name='j'/></robot>",
     r"^x\.urdf:3: joint 'j' is declared twice"),
    ("<robot>\n\n<joint name='j'><origin xyz='1 2'/></joint></robot>",
     r"^x\.urdf:3: origin xyz='1 2' is not three finite numbers"),
    ("<robot><joint name='j'><origin/><origin/></joint></robot>", r"^x\.urdf:1: joint 'j' has two <origin>"),
    ("<robot><joint type='fixed'/></robot>", r"^x\.urdf:1: a <joint> without a name"),
    ("<robot><joint name='k'><origin/></joint></robot>", r"^x\.urdf: no joint named 'j' \(its joints: k\)"),
    ("<robot>\n<joint name='j'/></robot>", r"^x\.urdf:2: joint 'j' has no child elements"),
])
def test_bad_urdfs_are_one_line_naming_file_and_line(text: str, message: str) -> None:
    with pytest.raises(InputError, match=message) as caught:
        rewrite_joint_origins_text(text, {"j": Origin((0.0,) * 3, (0.0,) * 3)}, "x.urdf")  # type: ignore[arg-type]
    assert "\n" not in str(caught.value)
