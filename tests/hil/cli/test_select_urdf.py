"""`hil select --urdf`: poses for an arm read from its URDF; what is a UR's alone refused in one line."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import hil.cli
from hil.arm.urdf_chain import chain_from_urdf
from tests.hil.robot_urdfs import arm as arm_urdf

FAST = ["--candidates", "600", "--count", "25", "--tracker", "1.8,0.4,0.5", "--no-bound", "--quiet"]


@pytest.fixture(autouse=True)
def only_select(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(hil.cli, "COMMAND_MODULES", ("select",))


def _run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    rc = hil.cli.main(argv)
    out, err = capsys.readouterr()
    return rc, out, err


def test_poses_for_a_kinova_from_its_urdf(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path, tip = arm_urdf("kinova")
    out = tmp_path / "poses.json"
    rc, _, err = _run(["select", "--urdf", str(path), "--tip", str(tip), *FAST, "--out", str(out)], capsys)
    assert rc == 0, err
    data = json.loads(out.read_text())
    assert data["urdf"]["file"] == path.name and data["urdf"]["tip"] == tip
    assert data["self_collision"]["check"] == "meshes"
    poses = np.array(data["poses"])
    assert poses.shape == (25, 6)
    assert np.all(chain_from_urdf(path, tip=tip).within_limits(poses))


@pytest.mark.parametrize(("extra", "message"), [
    (["--method", "time-aware"], "--method time-aware is modelled for Universal Robots arms only"),
    (["--compliance"], "--compliance is modelled for Universal Robots arms only"),
    (["--start", "0,0,0,0,0,0"], "--start"),
    (["--robot", "ur5e"], "--robot and --urdf both name the arm"),
])
def test_what_is_a_urs_alone_is_one_line(extra: list[str], message: str,
                                         capsys: pytest.CaptureFixture[str]) -> None:
    path, tip = arm_urdf("panda")
    rc, out, err = _run(["select", "--urdf", str(path), "--tip", str(tip), *FAST, *extra], capsys)
    assert rc == 2 and out == ""
    assert message in err and len(err.strip().splitlines()) == 1


def test_no_arm_at_all_is_one_line(capsys: pytest.CaptureFixture[str]) -> None:
    rc, _, err = _run(["select", *FAST], capsys)
    assert rc == 2 and "give --robot (a catalog UR) or --urdf FILE" in err
