"""hil identify --joint-errors: none, auto (cross-validated) and fixed orders; the model's blocks reach fk."""

from __future__ import annotations

import json

import numpy as np
import pytest

from hil.arm.joint_errors import JointErrors
from hil.arm.kinematics import Kinematics
from hil.calibration.measurements import write_measurements
from hil.calibration.synthetic import Noise, random_configurations, random_truth
from hil.cli import main


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    d = tmp_path_factory.mktemp("joint_errors")
    rng = np.random.default_rng(1)
    truth = random_truth("ur5e", rng, rigid=True)
    truth.joint_errors = JointErrors.of([[], [[1, 2e-4, -1e-4]], [], [[2, 1.5e-4, 1e-4]], [], []])
    q = random_configurations("ur5e", 60, rng)
    p = Kinematics(truth).points(q) + rng.normal(0, Noise(20e-6).tracker_sigma, (60, 3))
    write_measurements(d / "m.csv", q, p)
    held = random_configurations("ur5e", 5, rng)
    rows = "\n".join(",".join(repr(float(v)) for v in r) for r in held)
    (d / "joints.csv").write_text(f"q1,q2,q3,q4,q5,q6\n{rows}\n")
    return d, truth, held


def test_auto_is_the_default_and_writes_the_chosen_terms(data, capsys):
    d, truth, held = data
    out = d / "auto.json"
    assert main(["identify", "--robot", "ur5e", "--measurements", str(d / "m.csv"), "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "joint errors (auto): joint2.k1, joint4.k2" in text and "joint2.cos1" in text
    doc = json.loads(out.read_text())
    assert doc["joint_error_selection"]["groups"] == ["joint2.k1", "joint4.k2"]
    assert [len(t) for t in doc["joint_errors"]] == [0, 1, 0, 1, 0, 0]
    # fk predicts with the blocks (it goes through Kinematics)
    points = d / "p.csv"
    assert main(["fk", "--model", str(out), "--joints", str(d / "joints.csv"), "--out", str(points)]) == 0
    p = np.loadtxt(points, delimiter=",", skiprows=1)
    assert np.sqrt(np.mean(np.sum((p - Kinematics(truth).points(held)) ** 2, axis=1))) < 60e-6


def test_none_and_fixed_orders(data, capsys):
    d, _, _ = data
    none, fixed = d / "none.json", d / "fixed.json"
    assert main(["identify", "--robot", "ur5e", "--measurements", str(d / "m.csv"), "--joint-errors", "none",
                 "--out", str(none), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["joint_errors"] is None and info["parameters"] == 27
    assert "joint_errors" not in json.loads(none.read_text())
    assert main(["identify", "--robot", "ur5e", "--measurements", str(d / "m.csv"), "--joint-errors", "1",
                 "--out", str(fixed), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["parameters"] == 27 + 12 and info["joint_errors"]["request"] == "1"


def test_a_bad_value_is_one_line_and_exit_2(data, capsys):
    d, _, _ = data
    assert main(["identify", "--robot", "ur5e", "--measurements", str(d / "m.csv"), "--joint-errors", "9",
                 "--out", str(d / "bad.json")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--joint-errors" in err[0]
