"""The kinematics of arms from their URDFs (example-robot-data): forward kinematics against pinocchio's
model of the whole file, the identification Jacobian against finite differences, the identifiable set's
size against an independent rank (finite differences + SVD), and a UR5e through a URDF built from its
DH table against today's catalog path."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from hil.arm.chain import ur_chain
from hil.arm.geometry import Geometry, pose
from hil.arm.kinematics import (
    Kinematics,
    apply_update,
    generic_configurations,
    generic_geometry,
    identifiable_parameters,
    parameter_layout,
    parameter_names,
)
from hil.arm.urdf_chain import chain_from_text, chain_from_urdf
from hil.calibration.exports import to_urdf
from hil.errors import InputError
from tests.hil.robot_urdfs import ARMS, arm

SMR = np.array([0.012, -0.021, 0.047])


def _chain(name: str):
    path, tip = arm(name)
    return path, chain_from_urdf(path, tip=tip)


@pytest.mark.parametrize("name", sorted(ARMS))
def test_smr_positions_equal_pinocchio_on_the_whole_urdf(name: str) -> None:
    path, chain = _chain(name)
    geometry = Geometry.nominal(chain, smr=SMR, tracker=pose((2.0, 0.5, 0.3), (0.1, -0.2, 2.5)))
    full = pin.buildModelFromUrdf(str(path))
    data = full.createData()
    Q = generic_configurations(chain, 30, seed=5)
    ours = Kinematics(geometry).points(Q, frame="base")
    base_id = full.getFrameId(chain.urdf.base, pin.FrameType.BODY)
    tip_id = full.getFrameId(chain.urdf.tip, pin.FrameType.BODY)
    for q, p in zip(Q, ours, strict=True):
        qf = pin.neutral(full)
        for joint_name, qi in zip(chain.joint_names, q, strict=True):
            joint = full.joints[full.getJointId(joint_name)]
            if joint.nq == 2:
                qf[joint.idx_q:joint.idx_q + 2] = [np.cos(qi), np.sin(qi)]
            else:
                qf[joint.idx_q] = qi
        pin.framesForwardKinematics(full, data, qf)
        expected = (data.oMf[base_id].inverse() * data.oMf[tip_id]).act(SMR)
        np.testing.assert_allclose(p, expected, atol=1e-12)


@pytest.mark.parametrize("name", ["panda", "so100", "panda_finger"])
def test_jacobian_equals_finite_differences(name: str) -> None:
    _, chain = _chain(name)
    geometry = generic_geometry(chain)
    lo, hi = chain.sampling_range()
    Q = np.random.default_rng(2).uniform(lo, hi, size=(6, chain.dof))
    kin = Kinematics(geometry)
    _, J = kin.point_and_jacobian(Q)
    size = parameter_layout(chain.dof).size
    assert J.shape == (6, 3, size)
    h = 1e-7
    for k in range(size):
        d = np.zeros(size)
        d[k] = h
        plus = Kinematics(apply_update(geometry, d)).points(Q)
        minus = Kinematics(apply_update(geometry, -d)).points(Q)
        np.testing.assert_allclose((plus - minus) / (2 * h), J[:, :, k], atol=1e-6,
                                   err_msg=parameter_names(chain)[k])


def _finite_difference_rank(chain) -> int:
    """Rank of the position Jacobian by central differences of `apply_update` and an SVD: nothing of
    the analytic columns nor of the pivoted QR."""
    geometry = generic_geometry(chain)
    Q = generic_configurations(chain, 80, seed=11)
    size = parameter_layout(chain.dof).size
    h = 1e-6
    columns = []
    for k in range(size):
        d = np.zeros(size)
        d[k] = h
        plus, minus = apply_update(geometry, d), apply_update(geometry, -d)
        diff = Kinematics(plus).points(Q) - Kinematics(minus).points(Q)
        columns.append((diff / (2 * h)).ravel())
    J = np.array(columns).T
    J /= np.linalg.norm(J, axis=0)
    s = np.linalg.svd(J, compute_uv=False)
    return int(np.sum(s > 1e-6 * s[0]))


@pytest.mark.parametrize("name", sorted(ARMS))
def test_identifiable_set_size_equals_an_independent_rank(name: str) -> None:
    _, chain = _chain(name)
    idx = identifiable_parameters(chain)
    assert len(idx) == _finite_difference_rank(chain)
    # a serial arm measured by position: Everett, Driels & Mooring (1987) count 4R + 2P + 6 for a full
    # pose, three fewer with positions only (the SMR's orientation is not measured)
    revolute = chain.kinds.count("RZ")
    assert len(idx) == 4 * revolute + 2 * (chain.dof - revolute) + 3


def test_ur5e_through_a_urdf_of_its_dh_table_equals_the_catalog_path() -> None:
    nominal = Geometry.nominal("ur5e")
    chain = chain_from_text(to_urdf(nominal), tip="tool0", source="ur5e.urdf")
    assert chain.dof == 6
    assert chain.kinds == ur_chain("ur5e").kinds
    Q = generic_configurations("ur5e", 40)
    tracker = pose((2.1, -1.3, 0.4), (0.05, -0.08, 2.4))
    ours = Kinematics(Geometry.nominal(chain, smr=SMR, tracker=tracker)).points(Q)
    theirs = Kinematics(Geometry.nominal("ur5e", smr=SMR, tracker=tracker)).points(Q)
    np.testing.assert_allclose(ours, theirs, atol=1e-12)
    np.testing.assert_array_equal(identifiable_parameters(chain), identifiable_parameters("ur5e"))


def test_compliance_is_refused_for_an_arm_from_its_urdf() -> None:
    _, chain = _chain("panda")
    with pytest.raises(InputError, match="Universal Robots arms only"):
        Kinematics(generic_geometry(chain)).point_and_jacobian(np.zeros((1, 7)), compliance=True)
