"""`hil identify` on a 6-D CSV (the committed synthetic camera file) and on a several-reflector CSV:
the tool in the model, the orientation figures of the cross-validation, and the options' errors."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from hil.calibration.synthetic_tool import write_tool_csv
from hil.cli import main
from tests.hil.calibration.sixd_data import SIXD_CSV, sixd_set


def identify(csv: Path, out: Path, *extra: str) -> int:
    return main(["identify", "--robot", "ur10e", "--measurements", str(csv), "--out", str(out), *extra])


def test_a_6d_file_is_fitted_with_its_orientations(tmp_path, capsys) -> None:
    out = tmp_path / "m.json"
    noise = ("--position-noise", "0.0005", "--orientation-noise", "0.0005")
    assert identify(SIXD_CSV, out, "--json", *noise) == 0
    summary = json.loads(capsys.readouterr().out)
    doc = json.loads(out.read_text())
    assert summary["parameters"] == 30 and doc["better_than_nominal"] is True
    assert len(doc["tool_rpy"]) == 3 and "tool.rx" in doc["covariance"]["parameters"]
    assert doc["fit"]["pose_fit"]["orientation"] is True
    assert doc["fit"]["pose_fit"]["orientation_noise"] == pytest.approx(5e-4)
    orient = doc["cross_validation"]["orientation"]
    assert orient["calibrated"]["rms"] < orient["nominal"]["rms"]
    assert not any("not used" in n for n in summary.get("notes", []))


def test_a_several_reflector_file_fits_every_reflector(tmp_path, capsys) -> None:
    csv = tmp_path / "three.csv"
    write_tool_csv(csv, sixd_set(seed=8, reflectors=3, orientation=False)[1])
    out = tmp_path / "m.json"
    assert identify(csv, out) == 0
    doc = json.loads(out.read_text())
    assert len(doc["reflectors"]) == 3 and doc["reflectors"][0] == doc["smr"]
    assert {"reflector2.x", "reflector3.z"} <= {p["name"] for p in doc["parameters"]}
    assert doc["cross_validation"]["orientation"] is None
    assert "text" not in capsys.readouterr().err


@pytest.mark.parametrize("extra", [("--compliance",), ("--joint-errors", "1"), ("--orientation-noise", "0")])
def test_what_the_6d_fit_cannot_do_is_refused_in_one_line(tmp_path, capsys, extra) -> None:
    assert identify(SIXD_CSV, tmp_path / "m.json", *extra) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and extra[0] in err[0]


def test_a_noise_option_on_a_positions_file_is_refused(tmp_path, capsys) -> None:
    csv = tmp_path / "p.csv"
    write_tool_csv(csv, sixd_set(seed=8, orientation=False)[1])
    assert identify(csv, tmp_path / "m.json", "--position-noise", "0.001") == 2
    assert "--position-noise" in capsys.readouterr().err
