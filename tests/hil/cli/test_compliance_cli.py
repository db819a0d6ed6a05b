"""The compliant model on the command line: identify --compliance --payload, fk --payload, exports' header."""

from __future__ import annotations

import json

import numpy as np
import pytest

from hil.arm.payload import Payload
from hil.arm.physical import typical_compliance
from hil.calibration.measurements import read_joints, write_measurements
from hil.calibration.model_file import load_geometry
from hil.calibration.synthetic import Noise, measure, random_configurations, random_truth
from hil.cli import main

PAYLOAD = Payload(3.0, (0.0, 0.0, 0.05))


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    d = tmp_path_factory.mktemp("compliant")
    rng = np.random.default_rng(5)
    truth = random_truth("ur5e", rng, rigid=True)
    truth.payload, truth.compliance = PAYLOAD, typical_compliance("ur5e") * 1.1
    q = random_configurations("ur5e", 50, rng)
    q_read, p = measure(truth, q, Noise(20e-6, 0.0), rng)
    write_measurements(d / "m.csv", q_read, p)
    rows = "\n".join(",".join(map(str, r)) for r in q[:5])
    (d / "joints.csv").write_text(f"q1,q2,q3,q4,q5,q6\n{rows}\n")
    return d


@pytest.fixture(scope="module")
def model(data):
    out = data / "model.json"
    assert main(["identify", "--robot", "ur5e", "--measurements", str(data / "m.csv"), "--compliance",
                 "--payload", "3,0,0,0.05", "--out", str(out)]) == 0
    return out


def test_identify_prints_the_compliance(data, capsys):
    assert main(["identify", "--robot", "ur5e", "--measurements", str(data / "m.csv"), "--compliance",
                 "--payload", "3,0,0,0.05", "--out", str(data / "printed.json")]) == 0
    text = capsys.readouterr().out
    assert "compliance.j2" in text and "rad/Nm" in text


def test_identify_with_compliance_writes_the_blocks(model):
    out = model
    doc = json.loads(out.read_text())
    assert doc["payload"] == {"mass": 3.0, "com": [0.0, 0.0, 0.05]}
    assert len(doc["compliance"]) == 6
    names = [p["name"] for p in doc["parameters"]]
    assert "compliance.j3" in names and "compliance.j1" not in names
    assert "compliance.j3" in doc["covariance"]["parameters"]
    geometry, _ = load_geometry(out)
    assert geometry.compliant and geometry.payload == PAYLOAD


def test_fk_predicts_the_sag_for_the_payload_asked(data, model):
    runs = {}
    for label, extra in (("own", []), ("none", ["--payload", "0"]), ("heavy", ["--payload", "5,0,0,0.1"])):
        out = data / f"p-{label}.csv"
        assert main(["fk", "--model", str(model), "--joints", str(data / "joints.csv"), *extra,
                     "--out", str(out)]) == 0
        runs[label] = np.loadtxt(out, delimiter=",", skiprows=1)
    assert np.linalg.norm(runs["own"] - runs["none"], axis=1).max() > 20e-6
    assert np.linalg.norm(runs["heavy"] - runs["own"], axis=1).max() > 20e-6
    q, _ = read_joints(data / "joints.csv")
    assert len(runs["own"]) == len(q)


@pytest.mark.parametrize("fmt", ["urdf", "ros-kinematics"])
def test_rigid_exports_say_what_they_cannot_hold(data, model, fmt):
    out = data / f"export.{fmt}"
    assert main(["export", "--model", str(model), "--format", fmt, "--out", str(out)]) == 0
    head = out.read_text()[:1200]
    assert "RIGID GEOMETRY ONLY" in head and "rad/Nm" in head and "3 kg" in head
