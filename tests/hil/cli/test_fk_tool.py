"""`hil fk` on a model of a measured tool (a 6-D fit's ``tool_rpy``, several reflectors): every
reflector's position and the measured frame's orientation, against a forward kinematics written here
with numpy (each joint origin, then a rotation about its z axis) and orientations converted by scipy —
nothing of hil's kinematics or pinocchio's log/rpy in the expectation."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from hil.arm.geometry import Geometry
from hil.calibration.model_file import truth_document, write_json
from hil.calibration.synthetic import Noise, random_truth
from hil.cli import main

REFLECTORS = np.array([[0.0, 0.0, 0.0], [0.05, 0.01, -0.02], [-0.02, 0.06, 0.01]])


def homogeneous(rotation: np.ndarray, translation: np.ndarray) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = rotation, translation
    return T


def flange_in_base(g: Geometry, q: np.ndarray) -> np.ndarray:
    """Π origin_i · Rz(q_i), then the flange: the URDF chain, in numpy."""
    T = np.eye(4)
    for origin, angle in zip(g.joints, q, strict=True):
        T = T @ origin.homogeneous @ homogeneous(Rotation.from_euler("z", angle).as_matrix(), np.zeros(3))
    return T @ g.flange.homogeneous


@pytest.fixture
def tool_model(tmp_path: Path) -> tuple[Geometry, Path]:
    rng = np.random.default_rng(11)
    g = random_truth("ur5e", rng, rigid=True)  # placement errors and a tracker; no compliance or warm-up
    g.tool_rotation = Rotation.from_euler("xyz", [0.4, -0.3, 1.1]).as_matrix()
    g.reflectors = g.smr + REFLECTORS
    path = tmp_path / "tool.json"
    write_json(path, truth_document(g, Noise()))
    return g, path


def joints(tmp_path: Path, q: np.ndarray) -> Path:
    path = tmp_path / "q.csv"
    path.write_text("q1,q2,q3,q4,q5,q6\n" + "\n".join(",".join(repr(float(v)) for v in r) for r in q) + "\n")
    return path


@pytest.mark.parametrize("frame", ["tracker", "base"])
def test_fk_writes_every_reflector_and_the_measured_frames_orientation(tool_model, tmp_path, capsys, frame):
    g, model = tool_model
    q = np.random.default_rng(2).uniform(-2.5, 2.5, (6, 6))
    out = tmp_path / "p.csv"
    capsys.readouterr()
    assert main(["fk", "--model", str(model), "--joints", str(joints(tmp_path, q)), "--frame", frame,
                 "--out", str(out), "--json"]) == 0
    captured = capsys.readouterr()
    doc = json.loads(captured.out)
    assert "rotation vector" in captured.err and "Rz(yaw) Ry(pitch) Rx(roll)" in captured.err

    lines = out.read_text().splitlines()
    assert lines[0] == "x,y,z,x2,y2,z2,x3,y3,z3,rx,ry,rz,roll,pitch,yaw"
    table = np.array([[float(v) for v in line.split(",")] for line in lines[1:]])
    world = np.eye(4) if frame == "base" else np.linalg.inv(g.tracker.homogeneous)
    for n, qn in enumerate(q):
        T = world @ flange_in_base(g, qn)
        points = (T[:3, :3] @ (g.smr + REFLECTORS).T).T + T[:3, 3]
        rotation = Rotation.from_matrix(T[:3, :3] @ g.tool_rotation)
        expected = np.r_[points.ravel(), rotation.as_rotvec(), rotation.as_euler("xyz")]
        np.testing.assert_allclose(table[n], expected, rtol=0, atol=1e-9)
        pose = doc["poses"][n]
        np.testing.assert_allclose(pose["position"], points[0], rtol=0, atol=1e-9)
        np.testing.assert_allclose(pose["reflectors"], points, rtol=0, atol=1e-9)
        np.testing.assert_allclose(pose["rotation_vector"], rotation.as_rotvec(), rtol=0, atol=1e-9)
        np.testing.assert_allclose(pose["rpy"], rotation.as_euler("xyz"), rtol=0, atol=1e-9)
    assert doc["format"] == "hil-fk/1" and doc["frame"] == frame and doc["reflectors"] == 3
    assert "exp" in doc["orientation"]["rotation_vector"] and "Rz(yaw)" in doc["orientation"]["rpy"]


def test_fk_of_a_single_smr_model_keeps_its_three_columns(tool_model, tmp_path, capsys):
    g, _ = tool_model
    g.tool_rotation, g.reflectors = None, None
    model = tmp_path / "plain.json"
    write_json(model, truth_document(g, Noise()))
    q = np.random.default_rng(3).uniform(-2.5, 2.5, (4, 6))
    out = tmp_path / "p.csv"
    capsys.readouterr()
    assert main(["fk", "--model", str(model), "--joints", str(joints(tmp_path, q)), "--out", str(out),
                 "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    lines = out.read_text().splitlines()
    assert lines[0] == "x,y,z" and doc["orientation"] is None
    Ti = np.linalg.inv(g.tracker.homogeneous)
    for n, qn in enumerate(q):
        T = Ti @ flange_in_base(g, qn)
        expected = T[:3, :3] @ g.smr + T[:3, 3]
        np.testing.assert_allclose([float(v) for v in lines[n + 1].split(",")], expected, rtol=0, atol=1e-9)
        np.testing.assert_allclose(doc["poses"][n]["position"], expected, rtol=0, atol=1e-9)


def test_fk_flange_of_a_tool_model_is_the_flange_position(tool_model, tmp_path):
    g, model = tool_model
    q = np.random.default_rng(4).uniform(-2.5, 2.5, (3, 6))
    out = tmp_path / "f.csv"
    assert main(["fk", "--model", str(model), "--joints", str(joints(tmp_path, q)), "--point", "flange",
                 "--frame", "base", "--out", str(out)]) == 0
    lines = out.read_text().splitlines()
    assert lines[0] == "x,y,z"
    for n, qn in enumerate(q):
        np.testing.assert_allclose([float(v) for v in lines[n + 1].split(",")], flange_in_base(g, qn)[:3, 3],
                                   rtol=0, atol=1e-9)
