"""`hil select`: JSON (docs/design.md, Contracts: pose selection); one-line errors (exit 2) for bad input."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import hil.cli
from hil.arm.catalog import get_robot

FAST = ["--candidates", "1500", "--count", "12"]


@pytest.fixture(autouse=True)
def only_select(monkeypatch: pytest.MonkeyPatch) -> None:
    # Other subcommands live on other branches; the dispatcher must not need them here.
    monkeypatch.setattr(hil.cli, "COMMAND_MODULES", ("select",))


def _run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    rc = hil.cli.main(argv)
    out, err = capsys.readouterr()
    return rc, out, err


def test_json_contract(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "poses.json"
    rc, stdout, err = _run(["select", "--robot", "ur5e", *FAST, "--tracker", "2.5,0.5,0.5",
                            "--smr", "0.03,-0.02,0.045", "--seed", "3", "--out", str(out)], capsys)
    assert rc == 0, err
    assert stdout == ""
    data = json.loads(out.read_text())
    for key in ("robot", "index", "value", "bound", "method", "seconds", "poses", "percent_of_bound",
                "travel_time", "constraints", "candidates"):
        assert key in data
    assert data["robot"] == "ur5e" and data["index"] == "O1" and data["method"] == "tabu"
    poses = np.array(data["poses"])
    assert poses.shape == (12, 6)
    assert np.all(get_robot("ur5e").within_limits(poses))
    assert 0 < data["value"] <= data["bound"]
    assert data["percent_of_bound"] == pytest.approx(100 * data["value"] / data["bound"])
    assert data["travel_time"]["ordered"] <= data["travel_time"]["unordered"]
    assert data["constraints"]["tracker"] == [2.5, 0.5, 0.5]
    assert set(data["constraints"]["enabled"]) >= {"acceptance", "line-of-sight", "self-collision"}
    # Deterministic for a seed, and stdout when there is no --out.
    rc, stdout, _ = _run(["select", "--robot", "ur5e", *FAST, "--tracker", "2.5,0.5,0.5",
                          "--smr", "0.03,-0.02,0.045", "--seed", "3"], capsys)
    assert rc == 0
    assert json.loads(stdout)["poses"] == data["poses"]


def test_baseline_methods_and_options(capsys: pytest.CaptureFixture[str]) -> None:
    rc, stdout, err = _run(["select", "--robot", "UR10e", *FAST, "--method", "exchange", "--index", "o3",
                            "--disable", "self-collision,floor", "--start", "0,-1.57,1.57,-1.57,-1.57,0"],
                           capsys)
    assert rc == 0, err
    data = json.loads(stdout)
    assert data["method"] == "exchange" and data["index"] == "O3" and data["robot"] == "ur10e"
    assert {"self-collision", "floor"} <= set(data["constraints"]["disabled"])
    assert data["travel_time"]["start"] == [0, -1.57, 1.57, -1.57, -1.57, 0]


BAD = [
    (["--robot", "ur9", "--count", "30"], "unknown robot"),
    (["--robot", "ur5e", "--count", "5"], "too small"),
    (["--robot", "ur5e", "--count", "x"], "invalid int"),
    (["--robot", "ur5e", "--count", "30", "--index", "O7"], "unknown observability index"),
    (["--robot", "ur5e", "--count", "30", "--method", "annealing"], "unknown method"),
    (["--robot", "ur5e", "--count", "30", "--scaling", "log"], "column scaling"),
    (["--robot", "ur5e", "--count", "30", "--tracker", "1,2"], "--tracker"),
    (["--robot", "ur5e", "--count", "30", "--smr", "a,b,c"], "--smr"),
    (["--robot", "ur5e", "--count", "30", "--disable", "gravity"], "unknown constraint"),
    (["--robot", "ur5e", "--count", "30", "--keep-in", "0,0,1,1,1,0"], "keep-in"),
    (["--robot", "ur5e", "--count", "30", "--keep-in", "0,0,1"], "--keep-in"),
    (["--robot", "ur5e", "--count", "30", "--range", "5,1", "--tracker", "2,0,0"], "range"),
    (["--robot", "ur5e", "--count", "30", "--candidates", "0"], "--candidates"),
    (["--robot", "ur5e", "--count", "30", "--candidates", "20"], "exceeds"),
    (["--robot", "ur5e", "--count", "30", "--start", "0,0,0"], "--start"),
    (["--robot", "ur5e", "--count", "30", "--half-angle", "nan"], "--half-angle"),
    (["--robot", "ur5e", "--count", "12", "--candidates", "500", "--tracker", "2.5,0,0.5",
      "--half-angle", "0.001"], "'acceptance' removed the most"),
]


@pytest.mark.parametrize(("args", "message"), BAD, ids=[m for _, m in BAD])
def test_bad_input_is_one_line_exit_2_nothing_written(args: list[str], message: str, tmp_path: Path,
                                                      capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "poses.json"
    try:
        rc, stdout, err = _run(["select", *args, "--out", str(out)], capsys)
    except SystemExit as exc:  # argparse usage errors exit through the parser
        rc, (stdout, err) = int(exc.code or 0), capsys.readouterr()
    assert rc == 2
    assert message in err
    assert len(err.strip().splitlines()) == 1
    assert "Traceback" not in err and stdout == ""
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_unwritable_output(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("x")
    rc, _, err = _run(["select", "--robot", "ur5e", *FAST, "--out", str(blocker / "poses.json")], capsys)
    assert rc == 2 and "cannot write" in err and len(err.strip().splitlines()) == 1
