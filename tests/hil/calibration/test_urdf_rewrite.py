"""The calibrated-URDF writer: only the joint origins change, byte for byte, and the file it writes
loads in pinocchio (and urdfdom) with the calibrated chain's forward kinematics."""

from __future__ import annotations

import shutil
import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from hil.calibration.urdf_origins import (
    axis_rotation,
    joint_origin,
    origin_placement,
    placement_origin,
)
from hil.calibration.urdf_rewrite import (
    Origin,
    format_triple,
    locate_joints,
    rewrite_joint_origins,
    rewrite_joint_origins_text,
)
from hil.errors import InputError
from tests.hil.robot_urdfs import ARMS, RobotUrdf


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
    data = ARMS[arm].path.read_bytes()
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
    data = ARMS["ur5"].path.read_bytes()
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


# --- the calibrated chain written back: pinocchio's FK of the written file is the chain's -------------------

def _se3(origin_element: ET.Element | None) -> pin.SE3:
    if origin_element is None:
        return pin.SE3.Identity()
    def triple(key: str) -> tuple[float, float, float]:
        return tuple(float(v) for v in origin_element.get(key, "0 0 0").split())  # type: ignore[return-value]
    return origin_placement(Origin(triple("xyz"), triple("rpy")))


def _chain(arm: RobotUrdf) -> list[ET.Element]:
    """The URDF's joints from the base link to the tip link, in order (read with ElementTree, not with
    the module under test)."""
    root = ET.parse(arm.path).getroot()
    by_child = {j.find("child").get("link"): j for j in root.findall("joint")}  # type: ignore[union-attr]
    joints, link = [], arm.tip
    while link != arm.base:
        joint = by_child[link]
        joints.append(joint)
        link = joint.find("parent").get("link")  # type: ignore[union-attr]
    return joints[::-1]


def _axis(joint: ET.Element) -> np.ndarray:
    axis = joint.find("axis")
    return np.array([float(v) for v in (axis.get("xyz") if axis is not None else "1 0 0").split()])


def _calibrated_chain(arm: RobotUrdf, rng: np.random.Generator, scale: float):
    """The RZ chain of the URDF (M_i = A_{i-1}⁻¹·F_i·O_i·A_i, tip = A_N⁻¹·F_tip), each placement moved
    by a random se(3) step of size `scale`, and the origins to write for it."""
    placements, names, origins = [], [], {}
    fixed = pin.SE3.Identity()
    previous_axis = pin.SE3.Identity()
    last_fixed: tuple[str, pin.SE3] | None = None  # the last fixed joint before the tip, and F before it
    for joint in _chain(arm):
        origin = _se3(joint.find("origin"))
        if joint.get("type") == "fixed":
            last_fixed = (joint.get("name"), fixed)  # type: ignore[assignment]
            fixed = fixed * origin
            continue
        A = axis_rotation(_axis(joint))
        nominal = previous_axis.inverse() * fixed * origin * A
        calibrated = nominal * pin.exp6(pin.Motion(rng.normal(scale=scale, size=6)))
        written = joint_origin(previous_axis.inverse() * fixed, calibrated, A)
        origins[joint.get("name")] = placement_origin(written)
        placements.append((nominal, calibrated))
        names.append(joint.get("name"))
        fixed, previous_axis, last_fixed = pin.SE3.Identity(), A, None
    tip_nominal = previous_axis.inverse() * fixed
    tip = tip_nominal
    if last_fixed is not None:  # written into the last fixed joint: what follows it is the identity
        tip = tip_nominal * pin.exp6(pin.Motion(rng.normal(scale=scale, size=6)))
        name, before = last_fixed
        written = joint_origin(previous_axis.inverse() * before, tip, pin.SE3.Identity())
        origins[name] = placement_origin(written)
    return names, placements, (tip_nominal, tip), origins


def _chain_fk(placements: list[pin.SE3], tip: pin.SE3, q: np.ndarray) -> pin.SE3:
    T = pin.SE3.Identity()
    for M, angle in zip(placements, q, strict=True):
        T = T * M * pin.SE3(pin.exp3(np.array([0.0, 0.0, angle])), np.zeros(3))
    return T * tip


def _pinocchio_fk(xml: str, arm: RobotUrdf, names: list[str], q: np.ndarray) -> pin.SE3:
    model = pin.buildModelFromXML(xml)
    v = np.zeros(model.nv)
    for name, angle in zip(names, q, strict=True):
        v[model.joints[model.getJointId(name)].idx_v] = angle
    config = pin.integrate(model, pin.neutral(model), v)
    data = model.createData()
    pin.framesForwardKinematics(model, data, config)
    return data.oMf[model.getFrameId(arm.tip, pin.FrameType.BODY)]


@pytest.mark.parametrize("arm", sorted(ARMS))
def test_the_written_urdf_has_the_calibrated_chains_forward_kinematics(arm: str) -> None:
    """Joint placements (and the tip, where a fixed joint leads to it) moved by a few millimetres and
    milliradians; the file written for them loads in pinocchio and its FK at random postures is the
    calibrated chain's to 1e-9 m — and the unchanged chain is the original file's, so the chain form
    of the module docstring is the URDF's."""
    robot = ARMS[arm]
    rng = np.random.default_rng(11)
    names, placements, (tip_nominal, tip), origins = _calibrated_chain(robot, rng, 0.005)
    original = robot.path.read_text(encoding="utf-8")
    written = rewrite_joint_origins_text(original, origins, arm)
    for q in rng.uniform(-np.pi, np.pi, size=(20, len(names))):
        nominal = _chain_fk([p[0] for p in placements], tip_nominal, q)
        unchanged = _pinocchio_fk(original, robot, names, q)
        assert np.allclose(unchanged.homogeneous, nominal.homogeneous, atol=1e-9)
        calibrated = _chain_fk([p[1] for p in placements], tip, q)
        got = _pinocchio_fk(written, robot, names, q)
        assert np.linalg.norm(got.translation - calibrated.translation) < 1e-9
        assert np.linalg.norm(pin.log3(got.rotation.T @ calibrated.rotation)) < 1e-9
        assert np.linalg.norm(calibrated.translation - nominal.translation) > 1e-4  # the change shows


def test_axis_rotation_takes_z_onto_the_axis() -> None:
    for axis in ([0, 0, 1], [0, 0, -1], [1, 0, 0], [0, -1, 0], [0.3, -0.2, 0.9]):
        a = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
        assert np.allclose(axis_rotation(axis).rotation @ [0.0, 0.0, 1.0], a, atol=1e-15)
    assert axis_rotation([0, 0, 1]).isIdentity()


@pytest.mark.parametrize("arm", sorted(ARMS))
def test_the_written_urdf_loads_in_urdfdom(arm: str, tmp_path: Path) -> None:
    """urdfdom's own parser (`check_urdf`, Debian liburdfdom-tools; .ci/run installs it) accepts it."""
    check_urdf = shutil.which("check_urdf")
    if check_urdf is None:
        pytest.skip("check_urdf (Debian liburdfdom-tools) is not installed: urdfdom not checked")
    robot = ARMS[arm]
    _, _, _, origins = _calibrated_chain(robot, np.random.default_rng(5), 0.005)
    path = tmp_path / "calibrated.urdf"
    path.write_bytes(rewrite_joint_origins(robot.path.read_bytes(), origins, arm))
    result = subprocess.run([check_urdf, str(path)], capture_output=True, text=True, timeout=60, check=False)
    assert result.returncode == 0, result.stdout + result.stderr
