"""6-D and several-reflector measurements of arms from their URDFs (example-robot-data): the tool's
predicted reflectors and frame against pinocchio's forward kinematics of the whole file, the tool
Jacobian against finite differences, the identifiable set against an independent rank, a file written
from pinocchio's FK read back, and the fit recovering a synthetic truth (also through ``hil identify``
and ``hil validate``)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from hil.arm import tool_frame as tf
from hil.arm.chain import Chain
from hil.arm.geometry import Geometry
from hil.arm.kinematics import generic_configurations
from hil.arm.urdf_chain import chain_from_urdf
from hil.calibration.measurements import Measurements, joint_columns, read_measurements
from hil.calibration.pose_identification import identify_pose
from hil.calibration.synthetic import random_truth
from hil.calibration.synthetic_tool import measure_tool, random_tool, write_tool_csv
from hil.cli import main
from tests.hil.robot_urdfs import arm

SMR = np.array([0.012, -0.021, 0.047])
TOOL_RPY = (0.4, -0.3, 1.1)
EXTRA = np.array([[0.05, 0.01, 0.03], [-0.02, 0.06, 0.02]])  # further reflectors, flange frame (m)


def _chain(name: str) -> tuple[Path, Chain]:
    path, tip = arm(name)
    return path, chain_from_urdf(path, tip=tip)


def _pinocchio_tool(path: Path, chain: Chain, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(m, 3, 3) reflectors and (m, 3, 3) frames in the base link's frame, from pinocchio's model of the
    whole URDF: the tip link's placement times each reflector, times the tool rotation."""
    full = pin.buildModelFromUrdf(str(path))
    data = full.createData()
    base_id = full.getFrameId(chain.urdf.base, pin.FrameType.BODY)
    tip_id = full.getFrameId(chain.urdf.tip, pin.FrameType.BODY)
    offsets = np.vstack([SMR, SMR + EXTRA])
    R_tool = pin.rpy.rpyToMatrix(*TOOL_RPY)
    points, frames = [], []
    for q in Q:
        qf = pin.neutral(full)
        for joint_name, qi in zip(chain.joint_names, q, strict=True):
            joint = full.joints[full.getJointId(joint_name)]
            if joint.nq == 2:
                qf[joint.idx_q:joint.idx_q + 2] = [np.cos(qi), np.sin(qi)]
            else:
                qf[joint.idx_q] = qi
        pin.framesForwardKinematics(full, data, qf)
        M = data.oMf[base_id].inverse() * data.oMf[tip_id]
        points.append([M.act(s) for s in offsets])
        frames.append(M.rotation @ R_tool)
    return np.array(points), np.array(frames)


def _tool_geometry(chain: Chain) -> Geometry:
    g = Geometry.nominal(chain, smr=SMR)
    g.tool_rotation = pin.rpy.rpyToMatrix(*TOOL_RPY)
    g.reflectors = np.vstack([SMR, SMR + EXTRA])
    return g


@pytest.mark.parametrize("name", ["panda", "kinova", "panda_finger"])
def test_tool_prediction_equals_pinocchio_on_the_whole_urdf(name: str) -> None:
    path, chain = _chain(name)
    Q = generic_configurations(chain, 20, seed=4)
    points, frames = tf.predict(_tool_geometry(chain), Q, frame="base")
    expected_points, expected_frames = _pinocchio_tool(path, chain, Q)
    np.testing.assert_allclose(points, expected_points, atol=1e-12)
    np.testing.assert_allclose(frames, expected_frames, atol=1e-12)


@pytest.mark.parametrize("name", ["panda", "panda_finger"])
def test_tool_jacobian_equals_finite_differences(name: str) -> None:
    _, chain = _chain(name)
    g = tf.generic_tool(chain, 3, True)
    Q = generic_configurations(chain, 5, seed=2)[:5]
    _, _, J = tf.frame_and_jacobian(g, Q, True)
    width = tf.width(3, chain.dof)
    assert J.shape == (5, 3 * 3 + 3, width)
    h = 1e-7
    for k in range(width):
        d = np.zeros(width)
        d[k] = h
        p1, R1 = tf.predict(tf.apply_tool_update(g, d), Q)
        p0, R0 = tf.predict(tf.apply_tool_update(g, -d), Q)
        dp = (p1 - p0).reshape(len(Q), -1) / (2 * h)
        do = tf.rotation_residuals(R1, R0) / (2 * h)
        np.testing.assert_allclose(np.hstack([dp, do]), J[:, :, k], atol=2e-6, err_msg=f"column {k}")


def _finite_difference_rank(chain: Chain, reflectors: int, orientation: bool) -> int:
    """Rank of the tool Jacobian by central differences of `apply_tool_update` and an SVD: nothing of
    the analytic columns nor of the pivoted QR."""
    g = tf.generic_tool(chain, reflectors, orientation)
    Q = generic_configurations(chain, 60, seed=11)
    width = tf.width(reflectors, chain.dof)
    h = 1e-6
    columns = []
    for k in range(width):
        d = np.zeros(width)
        d[k] = h
        p1, R1 = tf.predict(tf.apply_tool_update(g, d), Q)
        p0, R0 = tf.predict(tf.apply_tool_update(g, -d), Q)
        parts = [(p1 - p0).reshape(len(Q), -1)]
        if orientation:
            parts.append(tf.rotation_residuals(R1, R0))
        columns.append(np.hstack(parts).ravel() / (2 * h))
    J = np.array(columns).T
    norms = np.linalg.norm(J, axis=0)
    J = J[:, norms > 0] / norms[norms > 0]  # the tool rotation's columns are zero without orientations
    s = np.linalg.svd(J, compute_uv=False)
    return int(np.sum(s > 1e-6 * s[0]))


@pytest.mark.parametrize(("name", "reflectors", "orientation"),
                         [("panda", 1, True), ("panda", 3, False), ("kinova", 2, True)])
def test_identifiable_tool_set_equals_an_independent_rank(name: str, reflectors: int,
                                                          orientation: bool) -> None:
    _, chain = _chain(name)
    idx = tf.identifiable_tool_parameters(chain, reflectors, orientation)
    assert len(idx) == _finite_difference_rank(chain, reflectors, orientation)
    # the position fit's 4R + 2P + 3, the frame's 3 angles with orientations, 3 per further reflector
    revolute = chain.kinds.count("RZ")
    position = 4 * revolute + 2 * (chain.dof - revolute) + 3
    assert len(idx) == position + (3 if orientation else 0) + 3 * (reflectors - 1)


def test_a_sixd_file_written_from_pinocchio_reads_back(tmp_path: Path) -> None:
    path, chain = _chain("panda")
    Q = generic_configurations(chain, 12, seed=8)
    points, frames = _pinocchio_tool(path, chain, Q)
    meas = Measurements(Q, points[:, 0].copy(), np.arange(2, 14), "x", "", frames, points)
    csv = tmp_path / "sixd.csv"
    write_tool_csv(csv, meas)
    assert csv.read_text().splitlines()[0].endswith(",".join(joint_columns(7)))
    back = read_measurements(csv, chain=chain)
    np.testing.assert_allclose(back.q, Q, atol=1e-12)
    np.testing.assert_allclose(back.reflectors, points, atol=1e-12)
    np.testing.assert_allclose(back.rotation, frames, atol=1e-12)


def _truth_and_data(chain: Chain, seed: int, count: int, reflectors: int,
                    orientation: bool) -> tuple[Geometry, Measurements, np.ndarray]:
    rng = np.random.default_rng(seed)
    truth = random_tool(random_truth(chain, rng, rigid=True), rng, reflectors, orientation)
    lo, hi = chain.sampling_range()
    q = rng.uniform(lo, hi, size=(count, chain.dof))
    meas = measure_tool(truth, q, rng, 20e-6, 1e-4 if orientation else None)
    return truth, meas, rng.uniform(lo, hi, size=(200, chain.dof))


@pytest.mark.parametrize(("name", "reflectors", "orientation"), [("panda", 3, True), ("z1", 2, False)])
def test_the_fit_recovers_a_synthetic_truth(name: str, reflectors: int, orientation: bool) -> None:
    _, chain = _chain(name)
    truth, meas, held_out = _truth_and_data(chain, 3, 40, reflectors, orientation)
    fit = identify_pose(meas, chain, position_noise=20e-6, orientation_noise=1e-4)
    assert len(fit.names) == len(tf.identifiable_tool_parameters(chain, reflectors, orientation))
    assert fit.names[-3:] == [f"reflector{reflectors}.{a}" for a in "xyz"]
    assert 0.8 < fit.pose_fit.scale < 1.2  # the noise as stated
    p_true, R_true = tf.predict(truth, held_out)
    p_fit, R_fit = tf.predict(fit.geometry, held_out)
    p_nominal, _ = tf.predict(fit.baseline, held_out)
    rms = np.sqrt(np.mean(np.sum((p_fit - p_true) ** 2, axis=2)))
    assert rms < 40e-6 < 0.5e-3 < np.sqrt(np.mean(np.sum((p_nominal - p_true) ** 2, axis=2)))
    if orientation:
        angle = np.sqrt(np.mean(np.sum(tf.rotation_residuals(R_true, R_fit) ** 2, axis=1)))
        assert angle < 1e-4


def test_hil_identify_and_validate_a_panda_sixd_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]
                                                     ) -> None:
    path, chain = _chain("panda")
    truth, meas, _ = _truth_and_data(chain, 4, 40, 2, True)
    lo, hi = chain.sampling_range()
    q_held = np.random.default_rng(5).uniform(lo, hi, size=(20, chain.dof))
    held = measure_tool(truth, q_held, np.random.default_rng(6), 20e-6, 1e-4)
    write_tool_csv(tmp_path / "m.csv", meas)
    write_tool_csv(tmp_path / "v.csv", held)
    urdf = ["--urdf", str(path), "--tip", str(chain.urdf.tip)]
    model = tmp_path / "model.json"
    assert main(["identify", *urdf, "--measurements", str(tmp_path / "m.csv"), "--position-noise", "2e-5",
                 "--orientation-noise", "1e-4", "--out", str(model)]) == 0
    doc = json.loads(model.read_text())
    names = [p["name"] for p in doc["parameters"]]
    assert {"tool.rx", "reflector2.x"} <= set(names) and "joint7.tx" in names
    assert "tool_rpy" in doc and len(doc["reflectors"]) == 2 and doc["urdf"]["tip"] == chain.urdf.tip
    capsys.readouterr()
    assert main(["validate", "--model", str(model), "--measurements", str(tmp_path / "v.csv"),
                 "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["rms"] < 60e-6 and out["tool"]["orientation"]["rms_rad"] < 3e-4
    assert out["tool"]["reflectors"] == 2 and out["tool"]["all_reflectors"]["rms"] < 60e-6
