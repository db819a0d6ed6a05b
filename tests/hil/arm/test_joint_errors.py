"""Angle-dependent joint errors and lost motion: the file block, the link angles, IK and sensitivities."""

from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
import pytest

from hil.arm.geometry import Geometry, pose
from hil.arm.ik import solve_ik
from hil.arm.joint_errors import JointErrors, motion_directions, parse_lost_motion
from hil.arm.kinematics import Kinematics
from hil.errors import InputError

TERMS = [[[1, 4e-5, -2e-5], [2, 1e-5, 3e-5]], [[1, -3e-5, 1e-5]], [], [[3, 2e-5, 0.0]],
         [[1, 1e-5, 1e-5], [200, 2e-6, -1e-6]], [[1, 5e-6, 0.0]]]
LOST = [2e-5, 4e-5, 3e-5, 1e-5, 1e-5, 5e-6]


def _arm() -> Geometry:
    g = Geometry.nominal("ur5e", smr=(0.02, -0.01, 0.05), tracker=pose((2.0, 0.5, 0.1), (0, 0, 2.9)))
    g.compliance = np.full(6, 2e-6)
    g.joint_errors = JointErrors.of(TERMS)
    g.lost_motion = np.array(LOST)
    return g


def test_offsets_are_the_contracts_sum_of_harmonics() -> None:
    q = np.random.default_rng(1).uniform(-3, 3, (20, 6))
    want = np.zeros_like(q)
    for j, terms in enumerate(TERMS):
        for k, a, b in terms:
            want[:, j] += a * np.cos(k * q[:, j]) + b * np.sin(k * q[:, j])
    np.testing.assert_allclose(JointErrors.of(TERMS).offsets(q), want, rtol=0, atol=1e-18)


def test_link_angles_apply_sag_then_errors_then_lost_motion() -> None:
    g = _arm()
    kin = Kinematics(g)
    q = np.random.default_rng(2).uniform(-3, 3, (5, 6))
    d = np.array([1, -1, 0, 1, -1, 1.0])
    sag = g.compliance * kin.gravity.torques(q)
    want = q - sag + g.joint_errors.offsets(q) - g.lost_motion * d
    np.testing.assert_allclose(kin.link_angles(q, d), want, atol=1e-16)
    # without directions no lost motion is applied
    np.testing.assert_allclose(kin.link_angles(q), q - sag + g.joint_errors.offsets(q), atol=1e-16)


def test_truth_and_model_files_round_trip_the_blocks(tmp_path) -> None:
    g = _arm()
    doc = json.loads(json.dumps(g.to_dict()))
    assert doc["joint_errors"] == TERMS
    assert doc["lost_motion"] == LOST
    back = Geometry.from_dict(doc)
    assert back.joint_errors == g.joint_errors
    np.testing.assert_array_equal(back.lost_motion, g.lost_motion)
    q = np.random.default_rng(3).uniform(-3, 3, (10, 6))
    np.testing.assert_array_equal(Kinematics(back).points(q, directions=np.ones(6)),
                                  Kinematics(g).points(q, directions=np.ones(6)))
    ideal = g.ideal()
    assert ideal.joint_errors is None and ideal.lost_motion is None
    assert "joint_errors" not in ideal.to_dict()


@pytest.mark.parametrize("block, value, words", [
    ("joint_errors", [[]] * 5, "6 joints"),
    ("joint_errors", [[[0, 1e-5, 0]]] + [[]] * 5, "whole number from 1"),
    ("joint_errors", [[[1.5, 1e-5, 0]]] + [[]] * 5, "whole number from 1"),
    ("joint_errors", [[[1, 0.5, 0]]] + [[]] * 5, "must be in [-0.01, 0.01] rad, got 0.5"),
    ("joint_errors", [[[1, float("nan"), 0]]] + [[]] * 5, "finite"),
    ("joint_errors", [[[1, 1e-5]]] + [[]] * 5, "[k, a, b]"),
    ("joint_errors", [[[1, 1e-5, 0], [1, 0, 1e-5]]] + [[]] * 5, "order twice"),
    ("lost_motion", [1e-5] * 5, "6 angles"),
    ("lost_motion", [1.0] + [0.0] * 5, "must be in [-0.03, 0.03] rad, got 1"),
])
def test_bad_blocks_are_one_line_naming_the_field(block, value, words) -> None:
    doc = Geometry.nominal("ur5e").to_dict()
    doc[block] = value
    with pytest.raises(InputError) as err:
        Geometry.from_dict(doc, "truth.json")
    assert str(err.value).startswith(f"truth.json: field '{block}")
    assert words in str(err.value)
    assert "\n" not in str(err.value)


def test_joint_sensitivities_match_finite_differences_of_the_link_angles() -> None:
    g = _arm()
    kin = Kinematics(g)
    q = np.random.default_rng(4).uniform(-3, 3, (4, 6))
    S = kin.joint_sensitivities(q)
    rigid = Kinematics(g.rigid())
    q_link = kin.link_angles(q)
    h = 1e-6
    for j in range(6):
        dq = np.zeros(6)
        dq[j] = h
        fd = (rigid.points(q_link + dq) - rigid.points(q_link - dq)) / (2 * h)
        np.testing.assert_allclose(S[:, :, j], fd, atol=1e-8)


def test_ik_returns_encoder_angles_whose_link_angles_reach_the_target() -> None:
    g = _arm()
    kin = Kinematics(g)
    q_true = np.array([0.3, -1.2, 1.4, -1.5, -1.2, 0.4])
    target = pin.SE3(kin.flange_poses(q_true)[0])
    q = solve_ik(kin, target, q_true + 0.05)
    np.testing.assert_allclose(q, q_true, atol=1e-9)
    assert not np.allclose(kin.link_angles(q)[0], q, atol=1e-6)  # the errors were there to undo


def test_motion_directions_remember_the_last_motion() -> None:
    prev = np.array([1.0, -1.0, 0.0, 1.0, 0.0, -1.0])
    d = motion_directions(np.zeros(6), np.array([0.1, 0.0, -0.2, 0.0, 0.0, 0.3]), prev)
    np.testing.assert_array_equal(d, [1, -1, -1, 1, 0, 1])


def test_parse_lost_motion_refuses_text() -> None:
    says = r"^m\.json: field 'lost_motion'\[0\]: expected a number, got \"a\"$"
    with pytest.raises(InputError, match=says):
        parse_lost_motion(["a"] * 6, "m.json")
