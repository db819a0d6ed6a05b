"""`hil validate` on a 6-D and a several-reflector file: every reflector the model knows and the
orientation error of a model with a tool frame, against errors put into the file by hand."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from hil.arm.geometry import Geometry
from hil.calibration.measurements import Measurements
from hil.calibration.model_file import truth_document, write_json
from hil.calibration.synthetic import Noise, random_configurations
from hil.calibration.synthetic_tool import measure_tool, write_tool_csv
from hil.cli import main
from tests.hil.calibration.sixd_data import tool_truth


def files(tmp_path: Path, reflectors: int, orientation: bool) -> tuple[Path, Measurements]:
    """A truth written as a model file and exact (noise-free) measurements of it at 12 poses."""
    rng = np.random.default_rng(4)
    truth = tool_truth("ur10e", rng, reflectors, orientation)
    model = tmp_path / "truth.json"
    write_json(model, truth_document(truth, Noise()))
    return model, measure_tool(truth, random_configurations("ur10e", 12, rng), rng, 0.0,
                               0.0 if orientation else None)


def validate(tmp_path: Path, model: Path, meas: Measurements, capsys) -> tuple[int, dict]:
    csv = tmp_path / "v.csv"
    write_tool_csv(csv, meas)
    code = main(["validate", "--model", str(model), "--measurements", str(csv), "--json",
                 "--max-rms", "0.001"])
    return code, json.loads(capsys.readouterr().out)


def test_the_orientation_error_is_the_angle_turned_into_the_file(tmp_path, capsys) -> None:
    model, meas = files(tmp_path, 1, True)
    code, exact = validate(tmp_path, model, meas, capsys)
    assert code == 0 and exact["tool"]["orientation"]["rms_rad"] < 1e-7 and exact["rms"] < 1e-7
    turn = pin.exp3(np.array([0.0, 0.0, 2e-3]))  # 2 mrad about the instrument's z
    turned = Measurements(meas.q, meas.p, meas.lines, meas.source, "", np.array([turn @ R for R in
                                                                                  meas.rotation]))
    code, out = validate(tmp_path, model, turned, capsys)
    assert out["tool"]["orientation"]["rms_rad"] == pytest.approx(2e-3, rel=1e-4)
    assert out["tool"]["orientation"]["max_rad"] == pytest.approx(2e-3, rel=1e-4)
    assert out["rms"] < 1e-7  # the positions were left as they were


def test_every_reflector_is_checked_and_judged(tmp_path, capsys) -> None:
    model, meas = files(tmp_path, 3, False)
    shifted = meas.reflectors.copy()
    shifted[:, 2, 0] += 2e-3  # the third reflector 2 mm off along x
    moved = Measurements(meas.q, shifted[:, 0].copy(), meas.lines, meas.source, "", None, shifted)
    code, out = validate(tmp_path, model, moved, capsys)
    per = out["tool"]["per_reflector"]
    assert [r["rms"] for r in per[:2]] == pytest.approx([0.0, 0.0], abs=1e-7)
    assert per[2]["rms"] == pytest.approx(2e-3, rel=1e-6)
    assert out["tool"]["all_reflectors"]["rms"] == pytest.approx(2e-3 / np.sqrt(3), rel=1e-6)
    assert out["rms"] < 1e-7 and code == 1  # the first alone would pass; all three fail 1 mm


def test_a_model_without_a_tool_frame_says_what_it_leaves_unchecked(tmp_path, capsys) -> None:
    _, meas = files(tmp_path, 1, True)
    csv = tmp_path / "v.csv"
    write_tool_csv(csv, meas)
    nominal = tmp_path / "nominal.json"
    write_json(nominal, truth_document(Geometry.nominal("ur10e"), Noise()))
    assert main(["validate", "--model", str(nominal), "--measurements", str(csv)]) in (0, 1)
    captured = capsys.readouterr()
    assert "orientations read but not checked" in captured.err
    assert captured.err.count("\n") == 1
