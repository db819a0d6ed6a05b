"""The report of an identification (`hil.report.model_report`, ``hil report --model``) for an arm from its
URDF, which no campaign drives: a Franka Panda of example-robot-data, synthetic truth, hil identify's
model. The per-pose figures are checked against the model's kinematics and the registered nominal arm
computed here, the verdict against its rule, and bad requests as one line, exit 2."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

from hil.arm.kinematics import Kinematics
from hil.calibration.identification import register
from hil.calibration.measurements import read_measurements
from hil.calibration.model_file import load_geometry, read_json
from hil.cli import main
from hil.errors import InputError
from hil.report.model_report import result_from_model
from tests.hil.robot_urdfs import arm


@pytest.fixture(scope="module")
def panda(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A Panda's synthetic measurements, validation poses and identified model (hil synth, identify)."""
    out = tmp_path_factory.mktemp("panda")
    path, tip = arm("panda")
    urdf = ["--urdf", str(path), "--tip", str(tip)]
    assert main(["synth", *urdf, "--poses", "40", "--validation", "30", "--seed", "5",
                 "--out-dir", str(out)]) == 0
    assert main(["identify", *urdf, "--measurements", str(out / "measurements.csv"),
                 "--out", str(out / "model.json")]) == 0
    return out


def _rms(errors: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.sum(np.asarray(errors) ** 2, axis=1))))


def test_per_pose_figures_are_the_models_and_the_registered_nominal_arms(panda: Path) -> None:
    geometry, doc = load_geometry(panda / "model.json")
    cal = read_measurements(panda / "measurements.csv", chain=geometry.chain)
    val = read_measurements(panda / "validation.csv", chain=geometry.chain)
    result = result_from_model(doc, "model.json", calibration=cal, validation=val)
    after = val.p - Kinematics(geometry).points(val.q)
    baseline = register(cal, geometry.chain, smr_guess=geometry.smr)
    before = val.p - Kinematics(baseline).points(val.q)
    np.testing.assert_allclose(result["per_pose"]["validation"]["after"], after, atol=1e-12)
    np.testing.assert_allclose(result["per_pose"]["validation"]["before"], before, atol=1e-12)
    assert result["validation"]["after"]["rms"] == pytest.approx(_rms(after), rel=1e-12)
    # the fit's own residuals: the model's RMS over the poses it kept
    used = np.asarray(result["per_pose"]["calibration"]["used"])
    assert used.sum() == doc["fit"]["used"]
    residuals = np.asarray(result["per_pose"]["calibration"]["after"])[used]
    assert _rms(residuals) == pytest.approx(doc["fit"]["rms"], rel=1e-9)
    # a calibrated Panda is tens of µm off on held-out poses, the nominal one millimetres
    assert _rms(after) < 60e-6 < 0.5e-3 < _rms(before)
    assert result["passed"] and result["verdict"]["rule"] == "auto"
    # the automatic rule: twice the cross-validated RMS (below the class bound for this reach)
    cv_rms = doc["cross_validation"]["calibrated"]["rms"]
    assert result["accept_rms"] == pytest.approx(2.0 * cv_rms)


def test_without_files_the_validation_is_the_models_cross_validation(panda: Path) -> None:
    doc = read_json(panda / "model.json")
    result = result_from_model(doc, "model.json")
    assert result["validation"]["after"] == doc["cross_validation"]["calibrated"]
    assert result["validation"]["before"] == doc["cross_validation"]["nominal"]
    assert any("cross-validation" in note for note in result["notes"])
    strict = result_from_model(doc, "model.json", accept_rms=1e-6)
    assert not strict["passed"] and strict["verdict"]["rule"] == "threshold"


def test_a_model_cross_validation_does_not_show_better_fails(panda: Path) -> None:
    doc = read_json(panda / "model.json")
    doc["better_than_nominal"] = False
    result = result_from_model(doc, "model.json", accept_rms=1.0)
    assert not result["passed"] and "nominal" in result["verdict"]["reason"]


def test_hil_report_model_renders_a_panda(panda: Path, capsys: pytest.CaptureFixture[str]) -> None:
    html = panda / "report.html"
    code = main(["report", "--model", str(panda / "model.json"), "--measurements",
                 str(panda / "measurements.csv"), "--validation", str(panda / "validation.csv"),
                 "--out", str(html)])
    assert code == 0
    assert "(PASS)" in capsys.readouterr().err
    text = html.read_text()
    geometry, doc = load_geometry(panda / "model.json")
    val = read_measurements(panda / "validation.csv", chain=geometry.chain)
    rms_mm = _rms(val.p - Kinematics(geometry).points(val.q)) * 1e3
    assert f"{rms_mm:.3f} mm" in text
    assert doc["urdf"]["sha256"] in text and "panda" in text
    assert f"{doc['urdf']['base']} → {doc['urdf']['tip']}, 7 joints" in text  # which chain of the URDF
    assert len(re.findall(r"<img ", text)) >= 3  # the per-pose figures are drawn
    assert "without interruption" not in text  # no campaign ran, none was suspended


def _one_line_exit_2(argv: list[str], capsys: pytest.CaptureFixture[str], *words: str) -> None:
    capsys.readouterr()
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    for word in words:
        assert word in err, err


def test_bad_requests_are_one_line_exit_2(panda: Path, tmp_path: Path,
                                          capsys: pytest.CaptureFixture[str]) -> None:
    model, out = str(panda / "model.json"), str(tmp_path / "r.html")
    # the calibration file must be the one the model was fitted to
    _one_line_exit_2(["report", "--model", model, "--measurements", str(panda / "validation.csv"),
                      "--out", out], capsys, "validation.csv", "fitted to")
    # a campaign's result holds its own measurements
    _one_line_exit_2(["report", "--result", model, "--validation", str(panda / "validation.csv"),
                      "--out", out], capsys, "--validation", "--model")
    # no cross-validation in the model and no held-out file
    doc = json.loads((panda / "model.json").read_text())
    del doc["cross_validation"]
    bare = tmp_path / "bare.json"
    bare.write_text(json.dumps(doc))
    _one_line_exit_2(["report", "--model", str(bare), "--out", out], capsys, "bare.json", "--validation")
    # a truth is not a model
    _one_line_exit_2(["report", "--model", str(panda / "truth.json"), "--out", out], capsys,
                     "truth.json", "hil-model/1")
    with pytest.raises(InputError, match="format"):
        result_from_model({"format": "hil-truth/1"}, "t.json")


def test_a_ur_model_renders_too(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A catalog UR's model (no URDF, no chain in its geometry) takes the same path."""
    assert main(["synth", "--robot", "ur5e", "--rigid", "--ideal", "--poses", "30", "--validation", "20",
                 "--seed", "2", "--out-dir", str(tmp_path)]) == 0
    model = tmp_path / "model.json"
    assert main(["identify", "--robot", "ur5e", "--joint-errors", "none", "--measurements",
                 str(tmp_path / "measurements.csv"), "--out", str(model)]) == 0
    geometry, doc = load_geometry(model)
    val = read_measurements(tmp_path / "validation.csv")
    result = result_from_model(doc, "model.json", validation=val)
    np.testing.assert_allclose(result["per_pose"]["validation"]["after"],
                               val.p - Kinematics(geometry).points(val.q), atol=1e-12)
    assert main(["report", "--model", str(model), "--validation", str(tmp_path / "validation.csv"),
                 "--out", str(tmp_path / "r.html")]) == 0
    assert "UR5E" in (tmp_path / "r.html").read_text()
