"""A chain from a real arm's URDF (example-robot-data) against pinocchio's own model of the whole file,
and every way a URDF can fail to be one chain: one InputError line each."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from hil.arm.urdf_chain import chain_from_text, chain_from_urdf
from hil.errors import InputError
from tests.hil.robot_urdfs import ARMS, arm, urdf_path

_DOF = {"panda": 7, "kinova": 6, "z1": 6, "so100": 5, "ur5": 6, "panda_finger": 8}


def _full_model_pose(path, chain, q: np.ndarray) -> np.ndarray:
    """The tip's pose in the base link's frame from pinocchio's model of the whole URDF at joints q."""
    full = pin.buildModelFromUrdf(str(path))
    data = full.createData()
    qf = pin.neutral(full)
    for name, qi in zip(chain.joint_names, q, strict=True):
        joint = full.joints[full.getJointId(name)]
        if joint.nq == 2:  # a continuous joint: (cos, sin)
            qf[joint.idx_q:joint.idx_q + 2] = [np.cos(qi), np.sin(qi)]
        else:
            qf[joint.idx_q] = qi
    pin.framesForwardKinematics(full, data, qf)
    base = data.oMf[full.getFrameId(chain.urdf.base, pin.FrameType.BODY)]
    return (base.inverse() * data.oMf[full.getFrameId(chain.urdf.tip, pin.FrameType.BODY)]).homogeneous


def _chain_pose(chain, q: np.ndarray) -> np.ndarray:
    M = pin.SE3.Identity()
    for kind, origin, qi in zip(chain.kinds, chain.origins, q, strict=True):
        motion = pin.SE3(pin.rpy.rpyToMatrix(0, 0, qi), np.zeros(3)) if kind == "RZ" else \
            pin.SE3(np.eye(3), np.array([0.0, 0.0, qi]))
        M = M * origin * motion
    return (M * chain.flange).homogeneous


@pytest.mark.parametrize("name", sorted(ARMS))
def test_chain_forward_kinematics_equals_pinocchio_on_the_whole_urdf(name: str) -> None:
    path, tip = arm(name)
    chain = chain_from_urdf(path, tip=tip)
    assert chain.dof == _DOF[name]
    assert chain.urdf is not None and chain.urdf.tip == tip
    rng = np.random.default_rng(3)
    lo, hi = chain.sampling_range()
    for q in rng.uniform(lo, hi, size=(25, chain.dof)):
        np.testing.assert_allclose(_chain_pose(chain, q), _full_model_pose(path, chain, q), atol=1e-12)


@pytest.mark.parametrize("name", sorted(ARMS))
def test_urdf_origins_of_the_nominal_chain_are_the_files_own(name: str) -> None:
    path, tip = arm(name)
    chain = chain_from_urdf(path, tip=tip)
    back = chain.urdf.urdf_origins(list(chain.origins))
    for joint in chain.urdf.joints:
        np.testing.assert_allclose(back[joint.name].homogeneous, joint.origin.homogeneous, atol=1e-12)


def test_a_prismatic_joint_becomes_a_translation_along_z() -> None:
    path, tip = arm("panda_finger")
    chain = chain_from_urdf(path, tip=tip)
    assert chain.kinds == ("RZ",) * 7 + ("PZ",)
    assert chain.lower[7] == 0.0 and chain.upper[7] == pytest.approx(0.04)


def test_limits_come_from_the_urdf() -> None:
    path, tip = arm("panda")
    chain = chain_from_urdf(path, tip=tip)
    assert chain.lower[3] == pytest.approx(-3.0718) and chain.upper[3] == pytest.approx(-0.0698)
    assert chain.velocity[0] == pytest.approx(2.1750)


def test_base_link_other_than_the_root() -> None:
    path, _ = arm("ur5")
    chain = chain_from_urdf(path, base="base_link", tip="tool0")
    assert chain.dof == 6 and chain.urdf.base == "base_link"
    q = np.full(6, 0.3)
    np.testing.assert_allclose(_chain_pose(chain, q), _full_model_pose(path, chain, q), atol=1e-12)


def _one_line(exc: pytest.ExceptionInfo[InputError]) -> str:
    text = str(exc.value)
    assert "\n" not in text
    return text


def test_missing_file_is_one_line(tmp_path) -> None:
    with pytest.raises(InputError) as exc:
        chain_from_urdf(tmp_path / "absent.urdf")
    assert "absent.urdf" in _one_line(exc)


def test_several_ends_name_the_candidates() -> None:
    with pytest.raises(InputError) as exc:
        chain_from_urdf(urdf_path(ARMS["ur5"][0]))
    text = _one_line(exc)
    assert "ur5_robot.urdf" in text and "ee_link" in text and "tool0" in text and "--tip" in text


def test_no_chain_between_base_and_tip() -> None:
    with pytest.raises(InputError) as exc:
        chain_from_urdf(urdf_path(ARMS["ur5"][0]), base="tool0", tip="base_link")
    assert "no chain" in _one_line(exc)


def test_unknown_link() -> None:
    with pytest.raises(InputError) as exc:
        chain_from_urdf(urdf_path(ARMS["ur5"][0]), tip="flange_of_nothing")
    assert "flange_of_nothing" in _one_line(exc)


@pytest.mark.parametrize("kind", ["floating", "planar"])
def test_unsupported_joint_type(kind: str) -> None:
    path, tip = arm("ur5")
    text = path.read_text().replace('name="elbow_joint" type="revolute"', f'name="elbow_joint" type="{kind}"')
    with pytest.raises(InputError) as exc:
        chain_from_text(text, tip=tip, source="bent.urdf")
    text = _one_line(exc)
    assert "bent.urdf" in text and "elbow_joint" in text and kind in text


def test_mimic_joint_on_the_chain() -> None:
    path, _ = arm("panda")
    with pytest.raises(InputError) as exc:
        chain_from_text(path.read_text(), tip="panda_rightfinger", source="panda.urdf")
    assert "panda_finger_joint2" in _one_line(exc) and "mimic" in _one_line(exc)


def test_malformed_xml() -> None:
    path, _ = arm("ur5")
    with pytest.raises(InputError) as exc:
        chain_from_text(path.read_text()[:500], source="cut.urdf")
    assert "cut.urdf" in _one_line(exc)
