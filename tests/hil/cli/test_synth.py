"""`hil synth` makes a real arm by default and the old rigid one with --rigid."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from hil.arm.joint_physics import standstill_sigma
from hil.cli import main


def synth(out: Path, *extra: str) -> dict:
    assert main(["synth", "--poses", "5", "--validation", "2", "--seed", "4", "--out-dir", str(out),
                 *extra]) == 0
    return json.loads((out / "truth.json").read_text())


def test_the_default_arm_is_compliant_loaded_and_warms_and_rigid_is_not(tmp_path: Path) -> None:
    real = synth(tmp_path / "real")
    rigid = synth(tmp_path / "rigid", "--rigid")
    assert len(real["compliance"]) == 6 and real["payload"]["mass"] > 0 and real["thermal"]["rise"] > 0
    assert not {"compliance", "payload", "thermal"} & rigid.keys()
    # one seed, one geometry: the blocks are all that differ
    for key in ("joints", "flange", "smr", "tracker"):
        assert real[key] == rigid[key]
    assert real["noise"]["encoder_sigma"] > 0
    # the poses (and their noise) are drawn the same way for both arms
    assert ((tmp_path / "real" / "measurements.csv").read_text().splitlines()[1].split(",")[:6]
            == (tmp_path / "rigid" / "measurements.csv").read_text().splitlines()[1].split(",")[:6])


def test_rigid_cannot_reshape_a_given_truth(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    synth(tmp_path / "a")
    capsys.readouterr()
    code = main(["synth", "--truth", str(tmp_path / "a" / "truth.json"), "--rigid", "--poses", "5",
                 "--out-dir", str(tmp_path / "b")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "--rigid" in err and len(err.splitlines()) == 1
    assert not (tmp_path / "b" / "truth.json").exists()


def test_ideal_leaves_out_joint_errors_and_lost_motion_and_no_ideal_adds_them(tmp_path: Path) -> None:
    ideal = synth(tmp_path / "ideal", "--ideal")
    real = synth(tmp_path / "real", "--no-ideal")
    assert "joint_errors" not in ideal and "lost_motion" not in ideal
    assert len(real["joint_errors"]) == 6 and len(real["lost_motion"]) == 6
    for key in ("joints", "flange", "smr", "tracker", "compliance", "payload", "thermal"):
        assert real[key] == ideal[key]  # one seed, one arm: only the two blocks differ
    # the realistic arm's truth carries its repeatability for a simulated station (the ideal arm none)
    assert real["noise"]["standstill_sigma"] == pytest.approx(standstill_sigma("ur5e"))
    assert ideal["noise"]["standstill_sigma"] == 0.0
    ideal_rows = (tmp_path / "ideal" / "measurements.csv").read_text().splitlines()[1:]
    real_rows = (tmp_path / "real" / "measurements.csv").read_text().splitlines()[1:]
    assert [r.split(",")[:6] for r in ideal_rows] == [r.split(",")[:6] for r in real_rows]
    assert [r.split(",")[6:] for r in ideal_rows] != [r.split(",")[6:] for r in real_rows]


def test_ideal_cannot_reshape_a_given_truth(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    synth(tmp_path / "a")
    capsys.readouterr()
    code = main(["synth", "--truth", str(tmp_path / "a" / "truth.json"), "--no-ideal", "--poses", "5",
                 "--out-dir", str(tmp_path / "b")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "--no-ideal" in err and "truth" in err and len(err.splitlines()) == 1
