"""`hil identify`, `validate` and `fk` read every measurements form (docs/design.md, Contracts:
Measurements CSV) and give what they give for the same numbers in hil's own form; a 6-D or
multi-reflector file is fitted on the first reflector's positions, and the command says so in one line."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from hil.calibration.measurements import read_measurements
from hil.cli import main

URDF = "shoulder_pan_joint,shoulder_lift_joint,elbow_joint,wrist_1_joint,wrist_2_joint,wrist_3_joint"


@pytest.fixture(scope="module")
def station(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("forms")
    assert main(["synth", "--robot", "ur5e", "--poses", "30", "--validation", "20", "--seed", "5",
                 "--out-dir", str(out)]) == 0
    return out


def table(path: Path, header: str, values: np.ndarray) -> Path:
    path.write_text(header + "\n" + "\n".join(",".join(repr(float(v)) for v in row) for row in values) + "\n")
    return path


def identify(capsys: pytest.CaptureFixture[str], measurements: Path, out: Path,
             *extra: str) -> tuple[dict, str]:
    capsys.readouterr()
    code = main(["identify", "--robot", "ur5e", "--measurements", str(measurements), "--out", str(out),
                 "--json", *extra])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    return json.loads(captured.out), captured.err


def same_fit(a: dict, b: dict) -> None:
    assert a["used"] == b["used"] and a["parameters"] == b["parameters"]
    assert a["rms"] == pytest.approx(b["rms"], rel=1e-6, abs=1e-12)
    assert a["max"] == pytest.approx(b["max"], rel=1e-6, abs=1e-12)


def test_identify_reads_degrees_polar_and_figaroh_files_as_their_cartesian_twin(station, tmp_path, capsys):
    meas = read_measurements(station / "measurements.csv")
    q, p = meas.q, meas.p
    base, err = identify(capsys, station / "measurements.csv", tmp_path / "base.json")
    assert "notes" not in base and "not used" not in err

    deg = table(tmp_path / "deg.csv", ",".join(f"q{i}_deg" for i in range(1, 7)) + ",x,y,z",
                np.hstack([np.degrees(q), p]))
    same_fit(identify(capsys, deg, tmp_path / "deg.json")[0], base)
    plain_deg = table(tmp_path / "plain.csv", "q1,q2,q3,q4,q5,q6,x,y,z", np.hstack([np.degrees(q), p]))
    same_fit(identify(capsys, plain_deg, tmp_path / "plain.json", "--joint-units", "deg")[0], base)

    # Leica polar readings computed here: Hz clockwise from +y, V from the zenith, slope distance in mm
    d = np.linalg.norm(p, axis=1)
    hz = np.degrees(np.arctan2(p[:, 0], p[:, 1])) % 360.0
    v = np.degrees(np.arccos(p[:, 2] / d))
    polar = table(tmp_path / "polar.csv", "q1,q2,q3,q4,q5,q6,hz_deg,v_deg,d_mm",
                  np.hstack([q, np.column_stack([hz, v, d * 1e3])]))
    same_fit(identify(capsys, polar, tmp_path / "polar.json")[0], base)

    # FIGAROH's marker header with one marker and no orientation: the same fit, nothing left unused
    # (files with orientations or further markers get the 6-D fit: tests/hil/cli/test_identify_sixd.py)
    figaroh = table(tmp_path / "figaroh.csv", f"x1,y1,z1,{URDF}", np.hstack([p, q]))
    info, err = identify(capsys, figaroh, tmp_path / "figaroh.json")
    same_fit(info, base)
    assert "notes" not in info and "not used" not in err


def test_validate_and_fk_read_degrees(station, tmp_path, capsys):
    model = tmp_path / "model.json"
    identify(capsys, station / "measurements.csv", model)
    val = read_measurements(station / "validation.csv")

    def stats(path: Path, *extra: str) -> dict:
        capsys.readouterr()
        assert main(["validate", "--model", str(model), "--measurements", str(path), "--json", *extra]) == 0
        return json.loads(capsys.readouterr().out)

    rad = stats(station / "validation.csv")
    deg = table(tmp_path / "vdeg.csv", "q1,q2,q3,q4,q5,q6,x,y,z", np.hstack([np.degrees(val.q), val.p]))
    assert stats(deg, "--joint-units", "deg")["rms"] == pytest.approx(rad["rms"], rel=1e-9)
    rotated = table(tmp_path / "v6.csv", "q1,q2,q3,q4,q5,q6,x,y,z,qw,qx,qy,qz",
                    np.hstack([val.q, val.p, np.tile([1.0, 0, 0, 0], (len(val), 1))]))
    six = stats(rotated)
    assert six["rms"] == pytest.approx(rad["rms"], rel=1e-12)
    assert "orientations read but not checked: the model has no tool frame" in six["notes"][0]

    def fk(path: Path, out: Path, *extra: str) -> np.ndarray:
        assert main(["fk", "--model", str(model), "--joints", str(path), "--out", str(out), *extra]) == 0
        return np.loadtxt(out, delimiter=",", skiprows=1)

    by_rad = fk(table(tmp_path / "q.csv", "q1,q2,q3,q4,q5,q6", val.q), tmp_path / "p1.csv")
    by_deg = fk(table(tmp_path / "qd.csv", ",".join(f"{n}_deg" for n in URDF.split(",")), np.degrees(val.q)),
                tmp_path / "p2.csv")
    np.testing.assert_allclose(by_deg, by_rad, rtol=0, atol=1e-12)
