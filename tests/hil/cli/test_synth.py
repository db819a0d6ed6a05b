"""`hil synth` makes a real arm by default and the old rigid one with --rigid."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

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
