"""The offline commands on arms from their URDFs (example-robot-data): synth → identify → validate / fk,
the model file carrying its URDF, and every bad URDF or mismatched file as one line, exit 2."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from hil.arm.geometry import Geometry
from hil.arm.kinematics import Kinematics
from hil.calibration.model_file import load_geometry, load_truth
from hil.cli import main
from tests.hil.robot_urdfs import arm


def _urdf(name: str) -> list[str]:
    path, tip = arm(name)
    return ["--urdf", str(path)] + ([] if tip is None else ["--tip", tip])


def _run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    capsys.readouterr()
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err.strip()


@pytest.mark.parametrize("name", ["panda", "z1"])
def test_synth_identify_validate_fk_round_trip(name: str, tmp_path: Path,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    code, _, _ = _run(capsys, "synth", *_urdf(name), "--poses", "40", "--validation", "30", "--seed", "3",
                      "--out-dir", str(tmp_path))
    assert code == 0
    truth, _ = load_truth(tmp_path / "truth.json")
    dof = truth.arm.dof
    header = (tmp_path / "measurements.csv").read_text().splitlines()[0]
    assert header == ",".join([f"q{k}" for k in range(1, dof + 1)] + ["x", "y", "z"])
    model = tmp_path / "model.json"
    code, _, _ = _run(capsys, "identify", *_urdf(name), "--measurements", str(tmp_path / "measurements.csv"),
                      "--out", str(model), "--json")
    assert code == 0
    doc = json.loads(model.read_text())
    urdf_path, tip = arm(name)
    assert doc["urdf"]["text"] == urdf_path.read_text() and doc["urdf"]["tip"] == tip
    assert len(doc["joints"]) == dof and len(doc["parameters"]) == 4 * dof + 3
    # validate and fk need nothing but the model file
    code, out, _ = _run(capsys, "validate", "--model", str(model), "--measurements",
                        str(tmp_path / "validation.csv"), "--json", "--max-rms", "0.0001")
    assert code == 0 and json.loads(out)["rms"] < 60e-6
    rows = np.loadtxt(tmp_path / "validation.csv", delimiter=",", skiprows=1)
    joints = tmp_path / "q.csv"
    joints.write_text(",".join(f"q{k}" for k in range(1, dof + 1)) + "\n"
                      + "\n".join(",".join(repr(float(v)) for v in r[:dof]) for r in rows) + "\n")
    code, _, _ = _run(capsys, "fk", "--model", str(model), "--joints", str(joints), "--frame", "base",
                      "--out", str(tmp_path / "p.csv"))
    assert code == 0
    predicted = np.loadtxt(tmp_path / "p.csv", delimiter=",", skiprows=1)
    geometry, _ = load_geometry(model)
    np.testing.assert_allclose(predicted, Kinematics(geometry).points(rows[:, :dof], frame="base"),
                               atol=1e-9)
    # in the tracker's frame (the base frame is the fit's own: the tracker pose absorbs joint 1's error)
    # the calibrated model is the truth to within the noise, the nominal arm millimetres off
    q = rows[:, :dof]
    true = Kinematics(truth).points(q)
    nominal = Geometry.nominal(truth.chain, smr=geometry.smr, tracker=geometry.tracker)
    assert np.sqrt(np.mean(np.sum((Kinematics(geometry).points(q) - true) ** 2, axis=1))) < 60e-6
    assert np.sqrt(np.mean(np.sum((Kinematics(nominal).points(q) - true) ** 2, axis=1))) > 0.5e-3


def _one_line_exit_2(result: tuple[int, str, str], *words: str) -> None:
    code, _, err = result
    assert code == 2, err
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    for word in words:
        assert word in err


def test_bad_urdfs_are_one_line_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    meas = tmp_path / "m.csv"
    meas.write_text("q1,q2,q3,q4,q5,q6,x,y,z\n" + "0,0,0,0,0,0,1,1,1\n" * 30)
    out = str(tmp_path / "model.json")
    identify = ("identify", "--measurements", str(meas), "--out", out)
    _one_line_exit_2(_run(capsys, *identify, "--urdf", str(tmp_path / "absent.urdf")), "absent.urdf")
    ur5, _ = arm("ur5")
    _one_line_exit_2(_run(capsys, *identify, "--urdf", str(ur5)), "ends", "tool0", "ee_link")
    _one_line_exit_2(_run(capsys, *identify, "--urdf", str(ur5), "--base", "tool0", "--tip", "base_link"),
                     "no chain")
    planar = tmp_path / "planar.urdf"
    planar.write_text(ur5.read_text().replace('name="elbow_joint" type="revolute"',
                                              'name="elbow_joint" type="planar"'))
    _one_line_exit_2(_run(capsys, *identify, "--urdf", str(planar), "--tip", "tool0"),
                     "planar.urdf", "elbow_joint", "planar")
    panda, _ = arm("panda")
    _one_line_exit_2(_run(capsys, *identify, "--urdf", str(panda), "--tip", "panda_rightfinger"), "mimic")
    _one_line_exit_2(_run(capsys, *identify, "--robot", "ur5e", "--tip", "tool0"), "--tip", "--urdf")
    _one_line_exit_2(_run(capsys, *identify, "--robot", "ur5e", "--urdf", str(ur5)), "--robot", "--urdf")
    assert not Path(out).exists()


def test_mismatched_files_and_ur_only_options_are_one_line(tmp_path: Path,
                                                           capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["synth", *_urdf("panda"), "--poses", "30", "--validation", "2", "--seed", "1",
                 "--out-dir", str(tmp_path)]) == 0
    meas = str(tmp_path / "measurements.csv")
    out = str(tmp_path / "model.json")
    _one_line_exit_2(_run(capsys, "identify", *_urdf("kinova"), "--measurements", meas, "--out", out),
                     "measurements.csv: line 1", "q1..q6", "kinova")
    _one_line_exit_2(_run(capsys, "identify", "--robot", "ur5e", "--measurements", meas, "--out", out),
                     "measurements.csv: line 1", "q7", "--urdf")
    for option in (["--compliance"], ["--joint-errors", "1"], ["--payload", "1,0,0,0.1"]):
        _one_line_exit_2(_run(capsys, "identify", *_urdf("panda"), *option, "--measurements", meas,
                               "--out", out), option[0], "Universal Robots")
    assert main(["identify", *_urdf("panda"), "--measurements", meas, "--out", out]) in (0, 1)
    _one_line_exit_2(_run(capsys, "export", "--model", out, "--format", "ros-kinematics", "--out",
                           str(tmp_path / "k.yaml"), "--force"), "ros-kinematics", "URDF")
